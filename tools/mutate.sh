#!/usr/bin/env bash
# tools/mutate.sh FILE 'OLD' 'NEW' -- COMMAND...
#
# A mutation check: does a test notice when the thing it checks is broken?
# Copies the repository's files (git ls-files, as they stand in the work
# tree) to a temporary directory, replaces there the first occurrence of the
# fixed string OLD by NEW in FILE, and runs COMMAND in that copy.  Prints
# "caught" if COMMAND fails (the mutant is killed) and exits 0, or "MISSED"
# if it passes and exits 1.  OLD not found in FILE, or OLD equal to NEW, is
# an error (exit 2): a mutation that changes nothing proves nothing.
#
#   tools/mutate.sh ray.c 'cos_theta / (real)PI' 'cos_theta' -- \
#       sh -c 'cc -O2 -o t tests/test_pt.c scene.c image.c cli.c kdtree.c bvh.c grid.c photons.c -lm && ./t'
#
# The mutations run against tests/test_pt.c, and what they gave, are in
# tools/mutations.txt.
set -u
usage() { echo "usage: tools/mutate.sh FILE 'OLD' 'NEW' -- COMMAND..." >&2; exit 2; }
[ $# -ge 5 ] && [ "$4" = "--" ] || usage
file=$1 old=$2 new=$3
shift 4
[ "$old" != "$new" ] || { echo "mutate.sh: OLD and NEW are the same string" >&2; exit 2; }
root=$(git rev-parse --show-toplevel 2>/dev/null) || { echo "mutate.sh: not in a git work tree" >&2; exit 2; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mutate.XXXXXX") || exit 2
trap 'rm -rf "$tmp"' EXIT

# the tracked files that exist in the work tree, with their directories
(cd "$root" && git ls-files -z | while IFS= read -r -d '' f; do
   [ -e "$f" ] && printf '%s\0' "$f"; done | tar --null -T - -cf -) | tar -xf - -C "$tmp" ||
  { echo "mutate.sh: cannot copy the repository" >&2; exit 2; }
[ -f "$tmp/$file" ] || { echo "mutate.sh: $file is not a tracked file" >&2; exit 2; }

# the first occurrence of OLD, as a fixed string, becomes NEW
python3 - "$tmp/$file" "$old" "$new" <<'EOF' || exit 2
import sys
path, old, new = sys.argv[1:4]
with open(path, encoding='utf-8', errors='surrogateescape') as f:
    text = f.read()
at = text.find(old)
if at < 0:
    sys.exit('mutate.sh: %r not found in %s' % (old, path.split('/', 3)[-1]))
with open(path, 'w', encoding='utf-8', errors='surrogateescape') as f:
    f.write(text[:at] + new + text[at + len(old):])
EOF

(cd "$tmp" && "$@") >"$tmp/.log" 2>&1
rc=$?
if [ "$rc" != 0 ]; then
  why=$(grep -m 2 '^FAIL ' "$tmp/.log" | cut -c1-150)
  [ -n "$why" ] || why=$(tail -n 1 "$tmp/.log" | cut -c1-150)
  echo "caught: $file '$old' -> '$new' (exit $rc)"
  printf '%s\n' "$why" | sed 's/^/    /'
  exit 0
fi
echo "MISSED: $file '$old' -> '$new' (the command passed)"
exit 1
