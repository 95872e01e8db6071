#!/usr/bin/env bash
# The code-golf corner (golf/README.md), quickly: the tools build cleanly,
# ctok counts what it says it counts, the squeezer keeps a program's meaning,
# every entry still prints its reference output (golf/score.sh --quick), and
# a one-character change to an entry's output is caught.
. tests/lib.sh

STRICT="-std=c99 -pedantic -Wall -Wextra -Werror"
for c in gcc clang; do
  command -v $c >/dev/null || { skip "golf/ctok.c and squeeze.c under $c: $c is not installed"; continue; }
  for tool in ctok squeeze; do
    check "golf/$tool.c builds without a warning under $c" \
      $c $STRICT -O2 -o "$TMP/$tool" golf/$tool.c
  done
done
$CC -O2 -o "$TMP/ctok" golf/ctok.c || { bad "cannot build golf/ctok.c"; exit 1; }
$CC -O2 -o "$TMP/squeeze" golf/squeeze.c || { bad "cannot build golf/squeeze.c"; exit 1; }

# ctok: bytes ioccc tokens lines cols
counts() { "$TMP/ctok" -r "$@"; }
expect() {  # NAME EXPECTED ACTUAL
  if [ "$2" = "$3" ]; then ok "$1"; else bad "$1: expected '$2', got '$3'"; fi
}
expect "ctok: { } ; before a blank are free in the IOCCC count" "8 1 4 1 8" \
  "$(printf '{ a; }\t\n' | counts)"
expect "ctok: a comment is no token; a splice does not part a token" "3" \
  "$(printf 'ab\\\ncd /* x y */ "s\\\ntr" 1e+5\n' | counts | cut -d' ' -f3)"
expect "ctok: maximal munch (a---b is a -- - b; x+++++y is five tokens)" "4 5" \
  "$(printf 'a---b' | counts | cut -d' ' -f3) $(printf 'x+++++y' | counts | cut -d' ' -f3)"
expect "ctok: the golf header and its /*! description are not scored" "3 1 2 1 2" \
  "$(printf '/* golf: ref=md5:x */\n/*! what\n and how */\nx;\n' | counts -g)"
expect "ctok: Heckbert's 1987 card is 882 tokens (888 as scored in 1987)" 882 \
  "$(gcc -E -P -x c golf/minray_1987.c | counts | cut -d' ' -f3)"

# The squeezer on a program full of places where a space matters.
cat >"$TMP/tricky.c" <<'EOF'
#include <stdio.h>
#define ADD (1+2)
#define F(x) ((x)*2)
#define SUM3(a,b,c) ((a)+(b)+(c)+(a)*(b)*(c)-(a)-(b)-(c)+F(a)+F(b)+F(c))
int main(void)
{
	int a = 5, b = -3, *p = &a;
	long big = 0x1e +1;              /* 0x1e+1 would be one bad pp-number */
	char s[] = "x" "y";
	int q = L"q"[0];                 /* L "q" and L"q" differ */
	printf("%d %d %d %d %d %ld\n", a - -b, a+ +b, a/ *p, ADD,
	       SUM3(a, b, a - -b), big + q);
	// a long string is cut with backslash-newline, so it stays one token
	printf("%s|%c|%s\n", "a string much wider than a narrow card \\ end",
	       '\'', s);
	a = a --- b; b = a ++ + ++ b;
	printf("%d %d %d\n", a, b, a <<= 1);
	return 0;
}
EOF
if $CC -w -o "$TMP/tricky" "$TMP/tricky.c"; then
  "$TMP/tricky" >"$TMP/tricky.want"
  want=$(counts "$TMP/tricky.c" | cut -d' ' -f3)
  for w in 8 13 80; do
    "$TMP/squeeze" -w $w "$TMP/tricky.c" >"$TMP/sq.c"
    read -r _ _ tok _ cols < <(counts "$TMP/sq.c")
    if $CC -w -o "$TMP/sq" "$TMP/sq.c" && "$TMP/sq" | cmp -s - "$TMP/tricky.want" &&
       [ "$tok" = "$want" ] && [ "$cols" -le $w ]; then
      ok "squeeze -w $w keeps a tricky program's output, tokens and width"
    else
      bad "squeeze -w $w changed a tricky program (tokens $tok of $want, width $cols)"
    fi
  done
else
  bad "the squeezer's sample does not compile with $CC"
fi

# The squeezer squeezed: the card it makes of itself still makes the cards.
cp golf/clex.h "$TMP/"
"$TMP/squeeze" -w 40 golf/squeeze.c >"$TMP/squeeze40.c"
if $CC -O2 -w -o "$TMP/squeeze40" "$TMP/squeeze40.c" &&
   "$TMP/squeeze40" golf/src/minray_tok.c | cmp -s - golf/minray_tok.c; then
  ok "squeeze.c squeezed to 40 columns squeezes golf/src/minray_tok.c alike"
else
  bad "squeeze.c squeezed to 40 columns behaves differently"
fi

# The entries, and the cards against their readable sources.
out=$(bash golf/score.sh --quick 2>&1)
rc=$?
printf '%s\n' "$out"
if [ $rc != 0 ] && ! printf '%s\n' "$out" | grep -q '^FAIL '; then
  bad "golf/score.sh --quick exited $rc: $(printf '%s\n' "$out" | tail -n 2)"
fi

# A one-character change in an entry's output must fail the check: a copy
# of the new card with one digit of its ambient light changed.
mkdir -p "$TMP/golf"
sed '0,/amb={.02,/s//amb={.03,/' golf/minray_tok.c >"$TMP/golf/changed.c"
if cmp -s golf/minray_tok.c "$TMP/golf/changed.c"; then
  bad "could not make the one-character change"
elif GOLF_DIR="$TMP/golf" bash golf/score.sh --quick >"$TMP/changed.out" 2>&1; then
  bad "a one-character change to an entry's output went unnoticed"
elif grep -q '^FAIL .*changed.c no longer prints its reference' "$TMP/changed.out"; then
  ok "a one-character change to an entry's output fails the golf check"
else
  bad "the changed entry failed for another reason: $(head -n 3 "$TMP/changed.out")"
fi

# A Monte Carlo card is judged by tools/ppmdiff within a tolerance; a
# stand-in ppmdiff here checks the harness hands it the right files.
rm -f "$TMP/golf/"*
cp golf/minray_tok.c "$TMP/golf/mc.c"
$CC -w -o "$TMP/mc" golf/minray_tok.c -lm && "$TMP/mc" >"$TMP/mc.ppm"
sed -i "1s|.*|/* golf: ref=psnr:40:$TMP/mc.ppm */|" "$TMP/golf/mc.c"
printf '#!/bin/sh\n[ "$1" = --psnr ] && [ "$2" = 40 ] && cmp -s "$3" "$4"\n' >"$TMP/ppmdiff"
chmod +x "$TMP/ppmdiff"
if PPMDIFF="$TMP/ppmdiff" GOLF_DIR="$TMP/golf" bash golf/score.sh --quick |
   grep -q '^PASS .*mc.c prints its reference'; then
  ok "a ref=psnr: entry is checked with ppmdiff --psnr"
else
  bad "a ref=psnr: entry is not checked with ppmdiff --psnr"
fi

# An entry this machine cannot build (as the 1987 card without gcc-multilib)
# is reported and skipped, not failed.
rm -f "$TMP/golf/"*
printf '/* golf: src=golf/minray_1987.c ref=md5:%s cc=gcc flags=-Wl,--no-such-option */\n' \
  61389114251af8c54260a89f79f529da >"$TMP/golf/nolink.golf"
if GOLF_DIR="$TMP/golf" bash golf/score.sh --quick >"$TMP/nolink.out" 2>&1 &&
   grep -q '^SKIP .*cannot build or run here' "$TMP/nolink.out"; then
  ok "an entry that cannot be built here is skipped, not failed"
else
  bad "an entry that cannot be built here: $(head -n 2 "$TMP/nolink.out")"
fi
