# kdtree.c: zero warnings, and kd_nearest / kd_any equal to brute force on
# 10^6 rays per scene (tests/test_kdtree.c; KD_QUICK=1 for 10^5 rays).
. tests/lib.sh

# The issue asks for no warnings under these; compilers that are missing are
# skipped.
for cc in gcc clang; do
  command -v $cc >/dev/null || continue
  check "kdtree.c has no warnings under $cc -std=c99 -pedantic -Wall -Wextra" \
    $cc -std=c99 -pedantic -Wall -Wextra -Werror -c kdtree.c -o "$TMP/kd_$cc.o"
done
if command -v tcc >/dev/null; then
  check "kdtree.c builds with tcc" tcc -c kdtree.c -o "$TMP/kd_tcc.o"
fi

if ! $CC $CFLAGS -o "$TMP/test_kdtree" tests/test_kdtree.c kdtree.c -lm 2>"$TMP/cc.err"; then
  bad "test_kdtree builds: $(head -c 300 "$TMP/cc.err" | tr '\n' ' ')"
  exit 1
fi
if [ -n "$KD_QUICK" ]; then export KD_RAYS=${KD_RAYS:-100000}; fi

# The scenes run side by side; their lines are printed in a fixed order.
scenes="same mesh grid thirds soup flat empty one"
for s in $scenes; do
  ( "$TMP/test_kdtree" "$s" >"$TMP/$s.out" 2>"$TMP/$s.err"; echo $? >"$TMP/$s.rc" ) &
done
wait
for s in $scenes; do
  cat "$TMP/$s.out"
  sed 's/^/    /' "$TMP/$s.err" | head -n 20
  rc=$(cat "$TMP/$s.rc")
  if [ "$rc" != 0 ] && ! grep -q '^FAIL ' "$TMP/$s.out"; then
    bad "test_kdtree $s exited $rc"
  fi
done
