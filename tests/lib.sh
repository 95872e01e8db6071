# Shared helpers for tests/*.test.sh (sourced, not run).
# ok NAME / bad NAME / skip NAME: WHY print the lines tests/run.sh counts (a
# check this machine cannot run is skipped, and says why); check NAME CMD...
# runs CMD and reports PASS when it exits 0.
ok()  { echo "PASS $*"; }
bad() { echo "FAIL $*"; }
skip() { echo "SKIP $*"; }
check() { local name=$1; shift; if "$@" >/dev/null 2>&1; then ok "$name"; else bad "$name"; fi; }
CC=${CC:-cc}
CFLAGS=${CFLAGS:--O2}
# What a program that includes ray.c whole links beside it (the Makefile's
# RAY_PARTS); word-split on purpose where it is used.
# tests/run.sh compiles them once and passes their objects (*.o) instead,
# compiled with CC and CFLAGS; RAY_SOURCES keeps the sources, for a build
# with flags of its own.
RAY_PARTS=${RAY_PARTS:-scene.c image.c cli.c kdtree.c bvh.c grid.c photons.c}
RAY_SOURCES=${RAY_SOURCES:-$RAY_PARTS}
# RAY_PARTS but the parts named (scene image ...): for a build that compiles
# those itself (with a -D of its own) or includes them.
parts_but() {
  local p n keep=
  for p in $RAY_PARTS; do
    n=${p##*/}; n=${n%.[co]}
    case " $* " in *" $n "*) ;; *) keep="$keep $p";; esac
  done
  echo "$keep"
}
export TMP=$(mktemp -d "${TMPDIR:-/tmp}/raytest.XXXXXX")
trap 'rm -rf "$TMP"' EXIT
# Python that reads a PFM's floats, for the tests' checkers: pfm(name) is
# the list of every pixel's r, g, b (python3 -c "$PFM_PY ...").
PFM_PY='
import sys, struct
def pfm(name):
    d = open(name, "rb").read()
    head = d.split(b"\n", 3)
    w, h = map(int, head[1].split())
    return struct.unpack("<%df" % (3 * w * h), head[3][:12 * w * h])
'
