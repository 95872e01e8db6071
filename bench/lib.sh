# bench/lib.sh - sourced by bench/run.sh and bench/pt.sh: their names for
# bench/table.c's subcommands (its top lists them all), built as $OUT/table.
# kv LOG KEY: KEY's value in a log of ./ray --stats=kv ("key value" lines),
# e.g. cpu_s, the render's CPU seconds (every thread; the scene's reading
# and the structure's build are not in it), or rays, every ray of any kind.
# spread V...: "least median greatest" of the values (the median of an even
# count: the mean of the two in the middle); median V...; range FORMAT V...:
# "least-greatest", each in FORMAT (printf's); ratios "A1 A2 ..." "B1 B2
# ...": A1/B1 A2/B2 ..., the pairs' ratios; ratio FORMAT A B: one;
# verdict A OP B: "met" or "NOT MET".
table() { "$OUT/table" "$@"; }
kv() { table kv "$@"; }
spread() { table spread "$@"; }
median() { table median "$@"; }
range() { table range "$@"; }
ratios() { table ratios "$@"; }
ratio() { table ratio "$@"; }
verdict() { table verdict "$@"; }
