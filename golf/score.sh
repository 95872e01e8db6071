#!/usr/bin/env bash
# golf/score.sh: the code-golf board behind `make golf`.
#   bash golf/score.sh            the leaderboard (see golf/README.md)
#   bash golf/score.sh --quick    the quick check for `make test`: each entry
#                                 built with $CC only, its output against its
#                                 reference; prints PASS/FAIL lines
# Exit status: 0 when every entry that can be built here prints its reference
# output and every card in golf/ matches the squeezed form of its readable
# source in golf/src/; 1 when one does not; 2 when an entry cannot be read
# (no header, a bad header field).  Compile warnings never fail: under strict
# flags they are the board's information, not an error.
# Everything built goes to a temporary directory, never into the tree.
# GOLF_DIR=DIR reads the entries from DIR instead of golf/ (the tests use it
# to show that a changed entry fails); the tools always come from golf/.
set -u
cd "$(dirname "$0")/.." || exit 2

QUICK=0
case ${1:-} in
--quick) QUICK=1 ;;
'') ;;
*) echo "usage: golf/score.sh [--quick]" >&2; exit 2 ;;
esac

CC=${CC:-cc}
CFLAGS=${CFLAGS:--O2}
COMPILERS="gcc clang tcc"
LENIENT="-w"
STRICT="-std=c99 -pedantic -Wall -Wextra"
DIR=${GOLF_DIR:-golf}
WIDTH=80   # golf/src/NAME.c squeezes to golf/NAME.c at this width
TMP=$(mktemp -d "${TMPDIR:-/tmp}/golf.XXXXXX") || exit 2
trap 'rm -rf "$TMP"' EXIT
# a runaway entry must not hang make test
TIMEOUT=$(command -v timeout >/dev/null && echo "timeout 120")

status=0
fail() { [ "$status" = 2 ] || status=1; }

# --- the tools, built here so the board never depends on a stale binary ----
for tool in ctok squeeze; do
  if ! $CC -O2 -o "$TMP/$tool" "golf/$tool.c" 2>"$TMP/$tool.err"; then
    echo "golf: cannot build golf/$tool.c with $CC:" >&2
    cat "$TMP/$tool.err" >&2
    exit 2
  fi
done

# --- header lines --------------------------------------------------------
# An entry's first line is   /* golf: key=value ... */   with the keys
#   ref=md5:HEX | ref=psnr:DB:FILE.ppm | ref=rmse:X:FILE.ppm   (required)
#   src=PATH   the entry's text is PATH (used by golf/NAME.golf pointers)
#   in=PATH    standard input       arg=WORD   one command-line argument
#   cc=a,b     the compilers whose output must match (default: all three)
#   flags=f,g  extra compiler flags, comma-separated (e.g. -m32)
#   pipe=CMD   a shell filter applied to the output before the comparison;
#              it takes the rest of the line
# Paths are relative to the repository root, where entries also run.
parse_header() {  # $1: the header line, $2: where it came from
  local h=$1 kv
  REF='' SRC='' IN='' ARG='' CCS='' FLAGS='' PIPE=''
  case $h in
  '/* golf:'*'*/'*) ;;
  *) return 1 ;;
  esac
  h=${h#'/* golf:'}
  h=${h%'*/'*}
  case $h in
  *' pipe='*) PIPE=${h#*' pipe='}; h=${h%%' pipe='*} ;;
  esac
  PIPE=${PIPE%"${PIPE##*[! ]}"}
  read -ra kvs <<<"$h"
  for kv in "${kvs[@]}"; do
    case $kv in
    ref=*) REF=${kv#ref=} ;;
    src=*) SRC=${kv#src=} ;;
    in=*) IN=${kv#in=} ;;
    arg=*) ARG=${kv#arg=} ;;
    cc=*) CCS=${kv#cc=} ;;
    flags=*) FLAGS=${kv#flags=} ;;
    *) echo "golf: $2: unknown header field '$kv'" >&2; return 2 ;;
    esac
  done
  case $REF in
  md5:????????????????????????????????) ;;
  psnr:*:*|rmse:*:*) ;;
  *) echo "golf: $2: ref= must be md5:HEX, psnr:DB:FILE or rmse:X:FILE" >&2
     return 2 ;;
  esac
  FLAGS=${FLAGS//,/ }
  CCS=${CCS//,/ }
  [ -n "$CCS" ] || CCS=$COMPILERS
  return 0
}

# --- the entries ---------------------------------------------------------
# ENTRY_FILE[i]: the C text; ENTRY_HEAD[i]: its header line.  A golf/*.golf
# file is a pointer: a header with src=, for texts that cannot carry a
# header line of their own (minray.c, the 1987 card as published).
ENTRY_FILE=() ENTRY_HEAD=()
pointed=" "
for g in "$DIR"/*.golf; do
  [ -e "$g" ] || continue
  IFS= read -r line <"$g"
  parse_header "$line" "$g"; rc=$?
  if [ $rc != 0 ] || [ -z "$SRC" ]; then
    [ $rc = 1 ] && echo "golf: $g: first line is not a golf header" >&2
    [ -z "$SRC" ] && [ $rc = 0 ] && echo "golf: $g: a pointer needs src=" >&2
    status=2; continue
  fi
  if [ ! -f "$SRC" ]; then
    echo "golf: $g: src=$SRC does not exist" >&2; status=2; continue
  fi
  ENTRY_FILE+=("$SRC") ENTRY_HEAD+=("$line")
  pointed+="$SRC "
done
for f in "$DIR"/*.c; do
  [ -e "$f" ] || continue
  case ${f##*/} in ctok.c|squeeze.c) continue ;; esac
  IFS= read -r line <"$f"
  parse_header "$line" "$f"; rc=$?
  if [ $rc = 1 ]; then
    case $pointed in *" $f "*) continue ;; esac
    echo "golf: $f: no golf header on line 1 (see golf/README.md)" >&2
    status=2; continue
  fi
  [ $rc = 0 ] || { status=2; continue; }
  ENTRY_FILE+=("$f") ENTRY_HEAD+=("$line")
done

have() { command -v "$1" >/dev/null 2>&1; }

printf 'int main(void){return 0;}\n' >"$TMP/probe.c"
# Can compiler $1 build anything at all with flags $2?  When it cannot, a
# failed build is this machine's limit (no gcc-multilib for -m32, a tcc
# without a 32-bit target), not the entry's fault.
can_build() {
  # shellcheck disable=SC2086
  $1 $2 -o "$TMP/probe" "$TMP/probe.c" >/dev/null 2>&1
}

PPMDIFF=${PPMDIFF:-}
find_ppmdiff() {
  [ -n "$PPMDIFF" ] && return 0
  if [ -x tools/ppmdiff ]; then PPMDIFF=tools/ppmdiff
  elif [ -f tools/ppmdiff.c ] &&
       $CC -O2 -o "$TMP/ppmdiff" tools/ppmdiff.c -lm 2>/dev/null; then
    PPMDIFF=$TMP/ppmdiff
  else return 1
  fi
}

# compare OUTFILE: 0 same, 1 different, 3 cannot be checked here
compare() {
  local kind=${REF%%:*} rest=${REF#*:} lim file
  case $kind in
  md5) [ "$(md5sum <"$1" | cut -c1-32)" = "$rest" ] ;;
  psnr|rmse)
    lim=${rest%%:*} file=${rest#*:}
    find_ppmdiff || return 3
    "$PPMDIFF" --"$kind" "$lim" "$1" "$file" >/dev/null 2>&1
    case $? in 0) return 0 ;; 1) return 1 ;; *) return 3 ;; esac ;;
  esac
}

# build CC OPT MODE FILE -> $TMP/bin; MODE lenient|strict.  Sets WARN to the
# number of warnings.  Returns the compiler's status.
build() {
  local extra=$LENIENT rc
  [ "$3" = strict ] && extra=$STRICT
  # shellcheck disable=SC2086
  $1 $2 $extra $FLAGS -o "$TMP/bin" "$4" -lm >"$TMP/cc.out" 2>&1; rc=$?
  WARN=$(grep -c 'warning:' "$TMP/cc.out")
  return $rc
}

# run FILE -> $TMP/out (after the pipe=); returns the entry's status
run() {
  local input=${IN:-/dev/null} rc
  set -- "$TMP/bin"
  [ -n "$ARG" ] && set -- "$@" "$ARG"
  # shellcheck disable=SC2086
  $TIMEOUT "$@" <"$input" >"$TMP/raw" 2>/dev/null; rc=$?
  if [ -n "$PIPE" ]; then
    bash -c "$PIPE" <"$TMP/raw" >"$TMP/out"
  else
    cp "$TMP/raw" "$TMP/out"
  fi
  return $rc
}

# check CC OPT FILE: build leniently and compare; echoes one word:
# same, differs, nobuild (the entry does not compile), cannot (this machine
# cannot build it), unchecked (no ppmdiff for a tolerance check)
check() {
  if ! build "$1" "$2" lenient "$3"; then
    if can_build "$1" "$FLAGS"; then echo nobuild; else echo cannot; fi
    return
  fi
  # built, but this machine cannot run what the flags make (a kernel
  # without 32-bit support runs no -m32 program): its limit, not the entry's
  if can_build "$1" "$FLAGS" && ! "$TMP/probe" 2>/dev/null; then echo cannot; return; fi
  run
  compare "$TMP/out"
  case $? in 0) echo same ;; 1) echo differs ;; *) echo unchecked ;; esac
}

# the compilers that must reproduce the entry, of those installed
run_set() {
  local c out=
  for c in $CCS; do have "$c" && out+="$c "; done
  echo "$out"
}

# --- the squeezed cards --------------------------------------------------
# golf/src/NAME.c is the readable source people edit; golf/NAME.c must be
# exactly what the squeezer makes of it.
squeeze_check() {
  local src card
  for src in "$DIR"/src/*.c; do
    [ -e "$src" ] || continue
    card=$DIR/$(basename "$src")
    "$TMP/squeeze" -w "$WIDTH" "$src" >"$TMP/squeezed.c" 2>"$TMP/sq.err"
    if [ ! -f "$card" ]; then
      echo "FAIL $src has no card $card (make golf-squeeze)"; fail
    elif cmp -s "$TMP/squeezed.c" "$card"; then
      echo "PASS $card is squeeze -w $WIDTH $src"
    else
      echo "FAIL $card is not squeeze -w $WIDTH $src (make golf-squeeze)"
      fail
    fi
  done
}

if [ $QUICK = 1 ]; then
  for i in "${!ENTRY_FILE[@]}"; do
    f=${ENTRY_FILE[$i]}
    parse_header "${ENTRY_HEAD[$i]}" "$f"
    cc=$CC
    case " $CCS " in
    *" $(basename "$CC") "*) ;;
    *) if [ "$CCS" != "$COMPILERS" ]; then
         cc=; for c in $CCS; do have "$c" && { cc=$c; break; }; done
       fi ;;
    esac
    if [ -z "$cc" ]; then
      echo "SKIP $f: none of its compilers ($CCS) is installed"; continue
    fi
    # shellcheck disable=SC2086
    case $(check "$cc" "$CFLAGS" "$f") in
    same) echo "PASS $f prints its reference ($cc $CFLAGS${FLAGS:+ $FLAGS})" ;;
    differs) echo "FAIL $f no longer prints its reference ($REF, $cc)"; fail ;;
    nobuild) echo "FAIL $f does not compile with $cc $CFLAGS $LENIENT $FLAGS"
             fail ;;
    cannot) echo "SKIP $f: cannot build or run here ($cc $FLAGS: this machine cannot link or run it)" ;;
    unchecked) echo "SKIP $f: no tools/ppmdiff for its $REF" ;;
    esac
  done
  squeeze_check
  exit $status
fi

# --- the board -----------------------------------------------------------
rows=$TMP/rows
: >"$rows"
notes=
for i in "${!ENTRY_FILE[@]}"; do
  f=${ENTRY_FILE[$i]}
  parse_header "${ENTRY_HEAD[$i]}" "$f"
  # bytes, IOCCC 2b and the card's size are taken on the text as written,
  # less its header line and /*! description (ctok -g); tokens on what the
  # preprocessor makes of it.
  read -r bytes ioccc _ lines cols < <("$TMP/ctok" -g -r "$f")
  cpp=gcc; have gcc || cpp=$CC
  # #include lines count as written (3 tokens for "#include <stdio.h>"):
  # the declarations of a system header are not the entry's text.
  inc=$(grep -E '^[[:space:]]*(#|%:)[[:space:]]*include' "$f" |
        "$TMP/ctok" -r | cut -d' ' -f3)
  # shellcheck disable=SC2086
  if grep -vE '^[[:space:]]*(#|%:)[[:space:]]*include' "$f" |
     $cpp -E -P $FLAGS -x c - >"$TMP/pp.c" 2>/dev/null; then
    tokens=$(( $("$TMP/ctok" -r "$TMP/pp.c" | cut -d' ' -f3) + inc ))
  else
    tokens="?"
  fi

  # Reference check: every compiler of the run set at -O0 and -O2.
  runs=0 same=0 bad='' cannot=0 unchecked=0
  declare -A LEN=()
  for c in $(run_set); do
    for opt in -O0 -O2; do
      r=$(check "$c" "$opt" "$f")
      case $r in
      same) runs=$((runs + 1)) same=$((same + 1)); LEN[$c]=ok ;;
      differs) runs=$((runs + 1)); bad+=" $c$opt"; LEN[$c]=ok ;;
      nobuild) runs=$((runs + 1)); bad+=" $c$opt:build"; LEN[$c]=err ;;
      cannot) cannot=$((cannot + 1)); LEN[$c]=n/a ;;
      unchecked) unchecked=$((unchecked + 1)); LEN[$c]=ok ;;
      esac
    done
  done
  if [ -n "$bad" ]; then
    output="NO $same/$runs"; fail
    notes+="  $f: output differs from $REF under$bad"$'\n'
  elif [ $runs -gt 0 ]; then output="same $same/$runs"
  elif [ $unchecked -gt 0 ]; then output="unchecked"
    notes+="  $f: no tools/ppmdiff to check $REF"$'\n'
  elif [ $cannot -gt 0 ]; then output="cannot build here"
    notes+="  $f: none of $CCS can build with '$FLAGS' here"$'\n'
  else output="no compiler"
  fi

  # Compile columns: lenient / strict, for every compiler installed.
  cells=
  for c in $COMPILERS; do
    if ! have "$c"; then cells+="$(printf '%-10s' '--')"; continue; fi
    len=${LEN[$c]:-}
    if [ -z "$len" ]; then
      if build "$c" -O2 lenient "$f"; then len=ok
      elif can_build "$c" "$FLAGS"; then len=err
      else len=n/a
      fi
    fi
    if [ "$len" = n/a ]; then strict=n/a
    elif build "$c" -O2 strict "$f"; then
      if [ "$WARN" = 0 ]; then strict=ok; else strict=${WARN}w; fi
    else strict=err
    fi
    if [ "$len" = n/a ]; then cell=n/a; else cell=$len/$strict; fi
    cells+="$(printf '%-10s' "$cell")"
  done
  unset LEN
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$tokens" "$bytes" "$f" \
    "$ioccc" "${lines}x$cols" "$cells" "$output" >>"$rows"
done

echo "Code-golf board: C tokens after the preprocessor (golf/ctok), fewest first"
echo
printf '%4s  %-21s %6s %6s %6s  %-7s  %-10s%-10s%-10s%s\n' \
  '#' entry tokens ioccc bytes card gcc clang tcc output
rank=0
sort -t $'\t' -k1,1n -k2,2n "$rows" |
while IFS=$'\t' read -r tokens bytes f ioccc card cells output; do
  rank=$((rank + 1))
  printf '%4s  %-21s %6s %6s %6s  %-7s  %s%s\n' \
    "$rank" "$f" "$tokens" "$ioccc" "$bytes" "$card" "$cells" "$output"
done
cat <<'EOF'

  tokens  C tokens of `cc -E -P` output; #include lines count as written
  ioccc   IOCCC rule 2b: non-blank characters; { } ; before a blank are free
  bytes, card (lines x widest line)   the file less its golf header line
          and the /*! description after it
  gcc clang tcc   lenient (-w) / strict (-std=c99 -pedantic -Wall -Wextra):
          ok, Nw = compiles with N warnings, err, n/a = cannot build here
  output  same N/M: N of M builds (each compiler of its cc=, -O0 and -O2)
          print the entry's reference; NO N/M: the others do not (see below)
EOF
if [ -n "$notes" ]; then echo; printf '%s' "$notes"; fi
echo
squeeze_check
exit $status
