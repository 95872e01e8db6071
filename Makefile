# make          build everything with -O2 (override: make CC=clang CFLAGS=-O3)
# make test     the test suite; ends with "N passed, N failed, N skipped"
# make stress   longer runs than make test: more rays for every acceleration structure, every SPD scene
# make wine     ray.exe (mingw-w64) run under Wine, its images byte for byte against ./ray's (tests/wine.sh)
# make farm     the README's GNU parallel and Slurm recipes, run for real here, merged and compared (tests/farm.sh)
# make bench    time against error, printed as a table and plotted to bench/out/
# make golf     the code-golf leaderboard (see golf/)
# make spd      the seven SPD scenes at the benchmark's sizes, generated into scenes/spd/
# make fuzz     libFuzzer on the scene readers (clang; fuzz/): builds build/fuzz/fuzz_sph,
#               fuzz_nff and fuzz_obj and runs each FUZZ_SECONDS (60; FUZZ_SECONDS=600 for longer;
#               FUZZ_SEED=N for libFuzzer's -seed)
# make install  ./ray and its manual page ray.1 into $(DESTDIR)$(PREFIX)/bin and
#               $(DESTDIR)$(PREFIX)/share/man/man1 (PREFIX=/usr/local); make uninstall removes them
# make clean    the programs, ray.1, build/, bench/out, scenes/spd and the images and partial renders made here (*.ppm, *.png, *.pfm, *.exr, *.part)
CC     ?= cc
CFLAGS ?= -O2
LDLIBS  = -lm
# OpenMP when the compiler has it (gcc, clang with libomp); ray.c builds without.
OMP    := $(shell echo 'int main(void){return 0;}' | $(CC) -fopenmp -x c - -o /dev/null 2>/dev/null && echo -fopenmp)
# No fused multiply-adds where the source has a multiply and an add: with
# -march=native a compiler may fuse them, and the images would depend on the
# machine (where coplanar triangles overlap).  ray.c asks for fma() by name
# where it wants one.
FP     := $(shell echo 'int main(void){return 0;}' | $(CC) -ffp-contract=off -x c - -o /dev/null 2>/dev/null && echo -ffp-contract=off)

PROGS = ray minray tools/ppmdiff tools/spd

all: $(PROGS) ray.1

# ray.c is the tracer; the files beside it read scenes (scene.c), write
# images (image.c), read the command line (cli.c), find hits (kdtree.c,
# bvh.c, grid.c) and photons (photons.c).  The tests and the fuzz targets include ray.c whole and
# link the rest: RAY_PARTS.
RAY_PARTS = scene.c image.c cli.c kdtree.c bvh.c grid.c photons.c
RAY_HEADERS = posix.h scene.h image.h cli.h kdtree.h bvh.h grid.h prims.h photons.h

ray: ray.c $(RAY_PARTS) $(RAY_HEADERS)
	$(CC) $(CFLAGS) $(FP) $(OMP) -o $@ ray.c $(RAY_PARTS) $(LDLIBS)

# ray's manual page, made from the one copy of each text: ./ray --help (cli.c's)
# for the options, the README's sentences for the rest (tools/man.awk); its
# date the last commit's (outside git, today).
ray.1: ray README.md tools/man.awk
	./ray --help | awk -v version="$$(./ray --version)" -v readme=README.md \
	  -v date="$$(git log -1 --date=short --format=%cd 2>/dev/null || date +%Y-%m-%d)" -f tools/man.awk >$@.tmp \
	  && mv $@.tmp $@ || { rm -f $@.tmp; exit 1; }

# The card is K&R C with implicit int: -w keeps its historical text quiet.
minray: minray.c
	$(CC) $(CFLAGS) -w -o $@ minray.c $(LDLIBS)

tools/ppmdiff: tools/ppmdiff.c
	$(CC) $(CFLAGS) -o $@ tools/ppmdiff.c $(LDLIBS)

tools/spd: tools/spd.c
	$(CC) $(CFLAGS) -o $@ tools/spd.c $(LDLIBS)

SPD_SCENES = balls_s4 gears_s4 mount_s6 rings_s7 teapot_s6 tetra_s6 tree_s11
spd: $(SPD_SCENES:%=scenes/spd/%.nff)

# scenes/spd/tree_s11.nff is "tools/spd tree 11"; written whole or not at all
scenes/spd/%.nff: tools/spd
	@mkdir -p scenes/spd
	tools/spd $(subst _s, ,$*) >$@.tmp && mv $@.tmp $@

# The fuzz targets: fuzz/fuzz_scene.c compiled once per format.
FUZZ_CC      ?= clang
FUZZ_CFLAGS  ?= -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
                -fno-omit-frame-pointer
FUZZ_SECONDS ?= 60
FUZZ_FORMATS  = sph nff obj
FORMAT_sph = SPH
FORMAT_nff = NFF
FORMAT_obj = OBJ

FUZZ_BUILD = $(FUZZ_CC) $(FUZZ_CFLAGS)

# the compiler and flags of the last build: the targets are rebuilt when they change
build/fuzz/flags: FORCE
	@mkdir -p build/fuzz
	@echo '$(FUZZ_BUILD)' | cmp -s - $@ || echo '$(FUZZ_BUILD)' >$@

build/fuzz/fuzz_%: fuzz/fuzz_scene.c ray.c $(RAY_PARTS) $(RAY_HEADERS) build/fuzz/flags
	$(FUZZ_BUILD) -DFORMAT=$(FORMAT_$*) -o $@ fuzz/fuzz_scene.c $(RAY_PARTS) -lm

# The seed corpora, build/fuzz/seeds-FORMAT: scenes/ and fuzz/seeds/, and for
# NFF the SPD scenes at size 1 (gears, too big at 19 kB, left out).
build/fuzz/seeds.made: $(wildcard scenes/*.sph scenes/*.nff scenes/*.obj fuzz/seeds/*) tools/spd
	rm -rf $(FUZZ_FORMATS:%=build/fuzz/seeds-%)
	mkdir -p $(FUZZ_FORMATS:%=build/fuzz/seeds-%)
	for f in $(FUZZ_FORMATS); do cp scenes/*.$$f fuzz/seeds/*.$$f build/fuzz/seeds-$$f/; done
	for db in balls mount rings teapot tetra tree; do tools/spd $$db 1 >build/fuzz/seeds-nff/spd_$$db.nff; done
	touch $@

fuzz: $(FUZZ_FORMATS:%=build/fuzz/fuzz_%) build/fuzz/seeds.made
	@FUZZ_SECONDS=$(FUZZ_SECONDS) FUZZ_SEED=$(FUZZ_SEED) bash fuzz/run.sh $(FUZZ_FORMATS)

test: all
	@CC="$(CC)" CFLAGS="$(CFLAGS)" RAY_PARTS="$(RAY_PARTS)" bash tests/run.sh

stress: all spd
	@CC="$(CC)" CFLAGS="$(CFLAGS)" RAY_PARTS="$(RAY_PARTS)" bash tests/stress.sh

wine: ray
	@CFLAGS="$(CFLAGS)" RAY_PARTS="$(RAY_PARTS)" bash tests/wine.sh

# The README's render-farm recipes run for real: GNU parallel, and a Slurm
# job array on a one-node cluster started here (root; tests/farm.sh).
farm: ray
	@bash -c 'out=$$(bash tests/farm.sh 2>&1); echo "$$out"; f=$$(grep -c "^FAIL" <<<"$$out"); \
	  echo "$$(grep -c "^PASS" <<<"$$out") passed, $$f failed, $$(grep -c "^SKIP" <<<"$$out") skipped"; [ $$f = 0 ]'

# What a user runs: ray and its page.  Not minray, the 1987 card: it takes
# no options and prints the one 32x32 image to stdout, which ./ray
# scenes/minray.sph renders too; it is a piece of history to read (minray.c)
# more than a command to keep on the PATH.
PREFIX ?= /usr/local
BINDIR  = $(PREFIX)/bin
MAN1DIR = $(PREFIX)/share/man/man1

install: ray ray.1
	mkdir -p $(DESTDIR)$(BINDIR) $(DESTDIR)$(MAN1DIR)
	cp ray $(DESTDIR)$(BINDIR)/ray
	chmod 755 $(DESTDIR)$(BINDIR)/ray
	cp ray.1 $(DESTDIR)$(MAN1DIR)/ray.1
	chmod 644 $(DESTDIR)$(MAN1DIR)/ray.1

uninstall:
	rm -f $(DESTDIR)$(BINDIR)/ray $(DESTDIR)$(MAN1DIR)/ray.1

bench: all spd
	@CC="$(CC)" CFLAGS="$(CFLAGS)" bash bench/run.sh

clean:
	rm -rf $(PROGS) ray.1 build bench/out scenes/spd
	rm -f *.ppm *.png *.pfm *.exr *.part

FORCE:

.PHONY: all test stress wine farm install uninstall bench clean golf spd fuzz FORCE
-include golf/golf.mk
