#!/usr/bin/env bash
# make install and make uninstall, staged under DESTDIR, and the manual page
# they install: rendered without a warning, every option of ./ray --help in
# it, each option's dashes minus signs.
. tests/lib.sh
make -s ray ray.1 >/dev/null 2>&1 || { bad "make ray ray.1"; exit 0; }
d=$TMP/stage
bin=$d/usr/bin/ray page=$d/usr/share/man/man1/ray.1
if make -s install DESTDIR="$d" PREFIX=/usr >"$TMP/make.out" 2>&1 && [ -x "$bin" ] && [ -f "$page" ] &&
   cmp -s ray "$bin" && cmp -s ray.1 "$page" && "$bin" --version | grep -q '^ray '; then
  ok "make install DESTDIR=... PREFIX=/usr: usr/bin/ray (it runs) and usr/share/man/man1/ray.1"
else
  bad "make install DESTDIR=... PREFIX=/usr: $(tail -n 2 "$TMP/make.out" | tr '\n' ' ')$(cd "$d" 2>/dev/null && find . -type f | tr '\n' ' ')"
fi

# The page as a reader sees it, in plain text (man-db's man, else groff,
# else mandoc), and what each formatter here warns of: man --warnings tells
# of macros, groff -ww of everything (fonts, escapes), mandoc of its own.
export LC_ALL=C MANWIDTH=80
renderer="" warners=""
if man --version 2>/dev/null | grep -q '^man [0-9]'; then       # man-db's
  renderer="man -l"
  man -l "$page" >"$TMP/page.txt" 2>/dev/null
elif command -v groff >/dev/null; then
  renderer="groff -man"
  groff -man -Tascii -P-cbou "$page" >"$TMP/page.txt" 2>/dev/null
elif command -v mandoc >/dev/null; then
  renderer="mandoc"
  mandoc -Tascii "$page" 2>/dev/null | col -b >"$TMP/page.txt"
fi
: >"$TMP/warnings"
warn() { local what=$1; shift; "$@" >/dev/null 2>>"$TMP/warnings"; warners="$warners, $what"; }
[ "$renderer" = "man -l" ] && warn "man --warnings" man --warnings -l "$page"
command -v groff >/dev/null && warn "groff -ww" groff -man -ww -z "$page"
command -v mandoc >/dev/null && warn "mandoc -W warning" mandoc -W warning -Tascii "$page"
if [ -z "$renderer" ]; then
  skip "ray.1 rendered: no man-db man, groff or mandoc here"
  skip "every option of --help in ray.1: nothing to render it with"
else
  if [ -s "$TMP/page.txt" ] && [ ! -s "$TMP/warnings" ] && grep -q '^NAME' "$TMP/page.txt"; then
    ok "ray.1 renders with $renderer; no warning from ${warners#, }"
  else
    bad "ray.1 with $renderer, warned by ${warners#, }: $(head -n 3 "$TMP/warnings" | tr '\n' ' ')"
  fi
  # each option line of --help an item of OPTIONS ("-o FILE" at the margin
  # of the items), and every option that --help names anywhere in the text
  ./ray --help >"$TMP/help"
  missing="" heads=0 names=0
  while read -r head; do
    heads=$((heads + 1))
    grep -qE "^       $head( |\$)" "$TMP/page.txt" || missing="$missing [$head]"
  done < <(sed -n 's/^  \(-[^ ]*\( [A-Z][^ ]*\)\{0,1\}\)  .*/\1/p' "$TMP/help")
  while read -r opt; do
    names=$((names + 1))
    grep -qE -- "(^|[^a-z0-9-])$opt([^a-z0-9-]|\$)" "$TMP/page.txt" || missing="$missing $opt"
  done < <(grep -oE '(^|[ (;])--?[a-z][a-z0-9=-]*' "$TMP/help" | sed 's/^[ (;]//' | sort -u)
  if [ -z "$missing" ] && [ "$heads" -ge 15 ]; then
    ok "ray.1 has every option of --help: $heads items, $names names"
  else
    bad "ray.1 lacks, of --help's $heads items and $names names:$missing"
  fi
fi
# An option's dashes are minus signs (\-) in the source: a hyphen may be
# typeset as U+2010 and a line may break after it, and neither can be
# typed back as the option.
hyphens=$([ -f "$page" ] && grep -v '^\.\\"' "$page" | grep -cE '(^|[ (;[])-[A-Za-z0-9-]')
if [ -f "$page" ] && [ "$hyphens" = 0 ]; then ok "ray.1 writes every option's dashes as \\- (minus signs)"
else bad "ray.1 has $hyphens lines with an option's dash as a hyphen: $(grep -v '^\.\\"' "$page" | grep -m 1 -E '(^|[ (;[])-[A-Za-z0-9-]' | cut -c1-80)"
fi

if make -s uninstall DESTDIR="$d" PREFIX=/usr >"$TMP/make.out" 2>&1 && [ ! -e "$bin" ] && [ ! -e "$page" ]; then
  ok "make uninstall removes both"
else
  bad "make uninstall: $(cd "$d" && find . -type f | tr '\n' ' ')"
fi
