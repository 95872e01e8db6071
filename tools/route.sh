#!/usr/bin/env bash
# tools/route.sh FILE FUNCTION...: where each function of a reader's route is
# defined in FILE, in the order given, and how many steps of the route go
# back up the file (a reader who follows the calls turns back there).
#   tools/route.sh ray.c main render render_row pixel_color ...
# A function not defined in FILE is reported as elsewhere and not counted.
set -u
file=$1; shift
prev=0 back=0 n=0
for f in "$@"; do
  # the last line that starts a definition of f: prototypes come first
  line=$(grep -n -E "^(static )?[A-Za-z_][A-Za-z0-9_ *]*[ *]$f\(" "$file" | grep -v -E '\);$' | tail -n 1 | cut -d: -f1)
  if [ -z "$line" ]; then printf '      %-22s elsewhere\n' "$f"; continue; fi
  n=$((n + 1))
  mark=" "
  if [ "$line" -lt "$prev" ]; then mark="^"; back=$((back + 1)); fi
  printf '%s %5d %s\n' "$mark" "$line" "$f"
  prev=$line
done
echo "$back backward jumps in $n stops"
