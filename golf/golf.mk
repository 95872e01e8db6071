# Included by the Makefile.  See golf/README.md.
#   make golf           the code-golf leaderboard; fails if an entry's output
#                       no longer matches its reference
#   make golf-squeeze   regenerate each card golf/NAME.c from its readable
#                       source golf/src/NAME.c
# Both build their tools in a temporary directory: nothing is left in the tree.
golf:
	@CC="$(CC)" bash golf/score.sh

golf-squeeze:
	@t=$$(mktemp -d) && trap 'rm -rf "$$t"' EXIT && \
	$(CC) -O2 -o "$$t/squeeze" golf/squeeze.c && \
	for s in golf/src/*.c; do \
	  "$$t/squeeze" -w 80 "$$s" > "$$t/card.c" && \
	  cp "$$t/card.c" "golf/$$(basename "$$s")" && \
	  echo "golf/$$(basename "$$s") <- $$s"; \
	done

.PHONY: golf-squeeze
