# The bugs the fuzz targets found (fuzz/crashes-found/README.md), each kept
# as a test now that ray.c is fixed: the glowing cone renders (under
# `make test` with sanitizers, CI's run, a read past the light table fails
# it) and without a NaN; the numbers that made NaN or made the tree and the
# loop disagree are refused at their file:line.
. tests/lib.sh
D=fuzz/crashes-found

nans() {  # the number of NaN floats in the PFM $1
  python3 -c 'import struct,sys,math
d=open(sys.argv[1],"rb").read(); h=d.split(b"\n",3); w,hh=map(int,h[1].split())
v=struct.unpack("<%df"%(3*w*hh) if float(h[2])<0 else ">%df"%(3*w*hh), d[-12*w*hh:])
print(sum(map(math.isnan,v)))' "$1"
}

for f in cone_glow cone_glow_light; do
  if ./ray -s 32x32 -n 4 -o "$TMP/$f.pfm" "$D/$f.sph" 2>"$TMP/err" \
     && [ "$(nans "$TMP/$f.pfm")" = 0 ]; then
    ok "$f: a glowing cone under the path tracer renders, no NaN"
  else
    bad "$f: $(head -c 200 "$TMP/err")"
  fi
done

refused() {  # $1 file, $2 line, $3 message
  if ./ray -s 8x8 -o "$TMP/x.pfm" "$D/$1" 2>"$TMP/err"; then
    bad "$1 rendered; expected $1:$2: $3"
  elif grep -q "^$D/$1:$2: $3" "$TMP/err" && [ ! -e "$TMP/x.pfm" ]; then
    ok "$1 refused at its line $2 ($3)"
  else
    bad "$1: got $(head -c 200 "$TMP/err")"
  fi
}
refused nan_refract.min.nff 14 "index of refraction must be between"
refused nan_huge.sph 3 "colours and weights must lie within 1e30"
refused cone_flat.sph 4 "cone shorter than 1e-9"
refused cone_flat.min.nff 10 "cone shorter than 1e-9"

# like_loop NAME WHAT: scene NAME.sph renders with every structure as with
# the loop over every object, the same floats
like_loop() {
  local a
  for a in kd bvh grid; do
    if ./ray -s 8x8 --accel none -o "$TMP/$1.none.pfm" "$D/$1.sph" 2>"$TMP/err" \
       && ./ray -s 8x8 --accel $a -o "$TMP/$1.$a.pfm" "$D/$1.sph" 2>>"$TMP/err" \
       && cmp -s "$TMP/$1.none.pfm" "$TMP/$1.$a.pfm"; then
      ok "$1: --accel $a renders $2 as the loop does"
    else
      bad "$1: --accel $a differs from the loop or fails $(head -c 200 "$TMP/err")"
    fi
  done
}

# grid_face: flat triangles on the scene box's far side, lost by the grid
like_loop grid_face "the triangles on the box's far side"

# bvh_thin: a centroid box thinner than a float step made bvh.c's bin index
# infinite, converted to int (undefined; UBSan stops it in CI's sanitizer run
# of make test)
like_loop bvh_thin "the thin mesh"
