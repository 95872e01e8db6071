# The business card: byte-exact under every installed compiler, and ray.c
# prints the same pixels from scenes/minray.sph.
. tests/lib.sh
want=61389114251af8c54260a89f79f529da
for cc in gcc clang tcc; do
  command -v $cc >/dev/null || { skip "minray.c md5 under $cc: $cc is not installed"; continue; }
  for opt in -O0 -O2; do
    if $cc $opt -w -o "$TMP/minray" minray.c -lm 2>"$TMP/err"; then
      got=$("$TMP/minray" | md5sum | cut -d' ' -f1)
      [ "$got" = $want ] && ok "minray.c md5 under $cc $opt" || bad "minray.c md5 under $cc $opt: $got, want $want"
    else
      bad "minray.c compiles under $cc $opt: $(head -1 "$TMP/err")"
    fi
  done
done
wc=$(wc -l < minray.c); cols=$(awk '{ if (length > m) m = length } END { print m }' minray.c)
[ "$wc" -le 25 ] && [ "$cols" -le 80 ] && ok "minray.c is a card: $wc lines, $cols columns" || bad "minray.c is $wc lines of $cols columns, over 25x80"

./minray > "$TMP/card.ppm"
./ray --p3 -o "$TMP/ray.ppm" scenes/minray.sph
cmp -s "$TMP/card.ppm" "$TMP/ray.ppm" && ok "ray -o x.ppm scenes/minray.sph prints minray's pixels byte for byte" \
  || bad "ray and minray differ on scenes/minray.sph: $(cmp "$TMP/card.ppm" "$TMP/ray.ppm")"
./ray -o "$TMP/ray6.ppm" scenes/minray.sph
[ "$(tail -c 3072 "$TMP/ray6.ppm" | od -An -v -tu1 | tr -s ' \n' '\n' | grep -v '^$' | md5sum)" = \
  "$(tail -n +4 "$TMP/card.ppm" | tr -s ' \n' '\n' | grep -v '^$' | md5sum)" ] \
  && ok "the default P6 output has the same pixel values" || bad "P6 pixel values differ from minray's"

# Threads: the same bytes with 1, 2 and 3 threads, on a scene that uses the
# kd-tree and every kind of object.  Only meaningful when ray has OpenMP.
./ray -t 2 -s 8x8 --stats -o "$TMP/t.ppm" scenes/mesh.sph 2> "$TMP/stats"
if grep -q "2 threads" "$TMP/stats"; then
  ./ray -t 1 -s 200x150 -n 3 -o "$TMP/t1.ppm" scenes/mesh.sph
  ./ray -t 2 -s 200x150 -n 3 -o "$TMP/t2.ppm" scenes/mesh.sph
  ./ray -t 3 -s 200x150 -n 3 -o "$TMP/t3.ppm" scenes/mesh.sph
  cmp -s "$TMP/t1.ppm" "$TMP/t2.ppm" && cmp -s "$TMP/t1.ppm" "$TMP/t3.ppm" \
    && ok "same bytes with 1, 2 and 3 threads" || bad "output depends on the thread count"
else
  skip "same bytes with 1, 2 and 3 threads: ray was built without OpenMP (one thread only)"
fi
