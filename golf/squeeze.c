/* squeeze: turn a readable C file into a card.
     squeeze [-w N] [FILE]       (N columns, 80 unless told; no FILE: stdin)
   It drops comments and every whitespace the compiler does not need, and
   packs the tokens into lines of at most N columns.  The tokens themselves
   are untouched, in order, so the card means what the source meant and
   counts the same number of tokens.

   Kept comments: a first line "/" "* golf: ... *" "/" (the entry's label, see
   golf/README.md) and every comment that opens with "/" "*!" (for what a
   card should say about itself).  Each is copied as written, on lines of
   its own, where it stood in the token stream.

   Where a space is needed: between two tokens A and B a space is written
   only if A and B side by side would not lex back to A first (a b, 1 .5,
   - -, / *, L "x", + ++ ...), by asking the same lexer ctok uses.
   Directives stay one logical line each; a directive wider than N is
   continued with backslash-newline.  A token wider than what is left of a
   line moves to the next line; one wider than N (a long string) is cut
   with backslash-newline, which translation phase 2 removes before the
   compiler sees tokens, so it still is one token.
   Not preserved: the spelling #x gives to macro arguments, which follows
   the whitespace inside them; squeezing changes "a + b" into "a+b". */
#include <stdio.h>
#include <stdlib.h>
#include "clex.h"

static int width = 80;
static int col;         /* columns used on the output line */
static int over;        /* kept comment lines wider than N */
static char prev[4096]; /* the last token written on this line, if any */
static size_t prevn;

static void usage(void)
{
	fputs("usage: squeeze [-w N] [FILE]\n", stderr);
	exit(2);
}

static void newline(void)
{
	if (col > 0)
		putchar('\n');
	col = 0;
	prevn = 0;
}

/* Would A immediately followed by B lex to something else than A, B? */
static int needspace(const char *a, size_t an, const char *b, size_t bn)
{
	char buf[8192];
	size_t n = an + bn;
	int kind;
	if (an == 0)
		return 0;
	/* "." "." "." would become "..." only by a third token; one space
	   between two dots is cheaper than looking ahead. */
	if (an == 1 && *a == '.' && *b == '.')
		return 1;
	if (n > sizeof buf)
		return 1;
	memcpy(buf, a, an);
	memcpy(buf + an, b, bn);
	return clex_one(buf, buf + n, 0, &kind) != an;
}

/* May a token be cut with backslash-newline before its byte k?  Not inside
   an escape sequence of a literal.  The standard removes the splice first
   (phase 2), so the cut would be harmless, but tcc 0.9.27 reads a backslash,
   a splice and an n as two characters instead of a newline; and an escape
   in one piece reads better anyway. */
static int cancut(const struct ctoken *t, size_t k)
{
	size_t j = 0, e;
	if (t->kind != T_STRING && t->kind != T_CHAR)
		return 1;
	while (j < t->n && t->s[j] != '"' && t->s[j] != '\'')
		j++;        /* the prefix: L, u, U or u8 */
	for (j++; j < t->n; j++) {
		if (t->s[j] != '\\')
			continue;
		e = j + 2;  /* one character, or the digits of \x.. and \ooo */
		if (e <= t->n && t->s[j + 1] == 'x')
			while (e < t->n && t->s[e] && strchr("0123456789abcdefABCDEF",
			                          t->s[e]))
				e++;
		else if (e <= t->n && t->s[j + 1] >= '0' && t->s[j + 1] <= '7')
			while (e < t->n && e < j + 4 && t->s[e] >= '0'
			       && t->s[e] <= '7')
				e++;
		if (k > j && k < e)
			return 0;
		j = e - 1;
	}
	return 1;
}

/* Write one token.  In a directive a line break must be spliced, and a
   column is kept free for the backslash. */
static void emit(const struct ctoken *t, int indir, int force)
{
	int sep = force || needspace(prev, prevn, t->s, t->n);
	int room = indir ? width - 1 : width;
	size_t i;
	/* break the line if the token does not fit, unless it is too wide
	   for any line and a piece of it still fits before the backslash */
	if (col > 0 && col + sep + (int)t->n > room
	    && ((int)t->n <= room || col + sep >= width - 1)) {
		if (indir) {
			fputs("\\\n", stdout);
			col = 0;
			if (sep) {
				putchar(' ');
				col = 1;
			}
		} else {
			newline();
		}
	} else if (col > 0 && sep) {
		putchar(' ');
		col++;
	}
	/* the rest does not fit: cut it, a backslash-newline after each
	   piece, never inside an escape sequence (see cancut) */
	for (i = 0; col + (int)(t->n - i) > room;) {
		size_t take = (size_t)(width - 1 - col);
		while (take > 0 && !cancut(t, i + take))
			take--;
		if (take == 0 && col == 0)   /* an escape wider than a line */
			take = (size_t)(width - 1);
		fwrite(t->s + i, 1, take, stdout);
		fputs("\\\n", stdout);
		col = 0;
		i += take;
	}
	fwrite(t->s + i, 1, t->n - i, stdout);
	col += (int)(t->n - i);
	if (t->n < sizeof prev) {
		memcpy(prev, t->s, t->n);
		prevn = t->n;
	} else {
		prevn = 0;
		putchar(' ');   /* a token that long is followed by a space */
		col++;
	}
}

static void keepcomment(const struct ctoken *t)
{
	size_t i;
	int c = 0;
	newline();
	for (i = 0; i < t->n; i++) {
		if (t->s[i] == '\n') {
			c = 0;
		} else if (++c > width) {
			over = 1;
		}
	}
	fwrite(t->s, 1, t->n, stdout);
	putchar('\n');
	col = 0;
	prevn = 0;
}

int main(int argc, char **argv)
{
	const char *path = NULL;
	FILE *f = stdin;
	char *text;
	size_t cap = 1 << 16, len = 0, r;
	int i, indir = 0, dirtok = 0, first = 1;
	struct clexer L;
	struct ctoken t;

	for (i = 1; i < argc; i++) {
		if (strcmp(argv[i], "-w") == 0 && i + 1 < argc) {
			width = atoi(argv[++i]);
			if (width < 8) {
				fputs("squeeze: width must be at least 8\n", stderr);
				return 2;
			}
		} else if (argv[i][0] == '-' && argv[i][1]) {
			usage();
		} else if (path) {
			usage();
		} else {
			path = argv[i];
		}
	}
	if (path && strcmp(path, "-") != 0 && !(f = fopen(path, "rb"))) {
		perror(path);
		return 2;
	}
	if (!(text = malloc(cap)))
		return perror("squeeze"), 2;
	while ((r = fread(text + len, 1, cap - len, f)) > 0) {
		len += r;
		if (len == cap) {
			char *nt = realloc(text, cap *= 2);
			if (!nt)
				return perror("squeeze"), 2;
			text = nt;
		}
	}
	if (ferror(f))
		return perror(path ? path : "stdin"), 2;
	len = clex_splice(text, len);

	clex_init(&L, text, len);
	while (clex_next(&L, &t) != T_END) {
		if (indir && !t.dir) {
			/* the directive ended at a newline: end its line */
			newline();
			indir = 0;
		}
		if (t.kind == T_COMMENT) {
			/* not inside a directive: its own lines would end it */
			if (!t.dir && ((first && t.n > 8
			    && memcmp(t.s, "/* golf:", 8) == 0)
			    || (t.n > 2 && t.s[1] == '*' && t.s[2] == '!')))
				keepcomment(&t);
			first = 0;
			continue;
		}
		first = 0;
		if (t.dirstart) {
			newline();
			indir = 1;
			dirtok = 0;
		}
		if (indir) {
			dirtok++;
			/* "#define f (x)" is object-like, "#define f(x)" is not:
			   keep the space the source had before that '(' */
			emit(&t, 1, dirtok == 4 && t.space && t.n == 1
			     && *t.s == '(');
		} else {
			emit(&t, 0, 0);
		}
	}
	newline();
	if (over)
		fprintf(stderr, "squeeze: a kept comment is wider than %d\n",
		        width);
	free(text);
	return ferror(stdout) ? 2 : 0;
}
