/* ctok: the golf scores of one C file.
     ctok [-g] [-r] [-l] [FILE]      (no FILE, or "-": standard input)
   prints
     bytes   the file's size
     ioccc   the IOCCC rule-2b count: characters that are not whitespace,
             except '{', '}' and ';' when whitespace or the end follows
     tokens  C tokens: every identifier or keyword, constant, string
             literal, character constant and punctuator counts one;
             comments and whitespace count nothing.  Adjacent string
             literals count one each (they are joined only in phase 6).
     lines, cols   the card's size: lines x widest line (a tab goes to the
             next multiple of 8 columns)
   -g  a first line "/" "* golf: ... *" "/" is the entry's label, not its
       text: it is left out of every count, and so is a comment opening
       with "/" "*!" right on the next line (the entry's description).
   -r  print the five numbers alone, in that order (for scripts).
   -l  list the tokens, one a line, as kind and spelling.
   "Tokens after the preprocessor" is this count taken on the output of
   cc -E -P: golf/score.sh does that; ctok itself does not expand macros. */
#include <stdio.h>
#include <stdlib.h>
#include "clex.h"

static const char *kindname[] = { "end", "ident", "number", "char",
	"string", "header", "punct", "other", "comment" };

static void usage(void)
{
	fputs("usage: ctok [-g] [-r] [-l] [FILE]\n", stderr);
	exit(2);
}

/* Read a whole stream; the caller frees.  Exits on failure: a count of a
   file that could not be read would be a wrong score. */
static char *slurp(FILE *f, size_t *len)
{
	size_t cap = 1 << 16, n = 0, r;
	char *b = malloc(cap);
	if (!b) {
		perror("ctok");
		exit(2);
	}
	while ((r = fread(b + n, 1, cap - n, f)) > 0) {
		n += r;
		if (n == cap) {
			char *nb = realloc(b, cap *= 2);
			if (!nb) {
				perror("ctok");
				exit(2);
			}
			b = nb;
		}
	}
	if (ferror(f)) {
		perror("ctok");
		exit(2);
	}
	*len = n;
	return b;
}

int main(int argc, char **argv)
{
	int raw = 0, list = 0, golf = 0, i;
	const char *path = NULL;
	FILE *f = stdin;
	char *text, *spliced;
	size_t len, slen, k, bytes, ioccc = 0, tokens = 0, lines = 0, cols = 0;
	size_t col = 0;
	struct clexer L;
	struct ctoken t;

	for (i = 1; i < argc; i++) {
		if (strcmp(argv[i], "-r") == 0)
			raw = 1;
		else if (strcmp(argv[i], "-l") == 0)
			list = 1;
		else if (strcmp(argv[i], "-g") == 0)
			golf = 1;
		else if (argv[i][0] == '-' && argv[i][1])
			usage();
		else if (path)
			usage();
		else
			path = argv[i];
	}
	if (path && strcmp(path, "-") != 0 && !(f = fopen(path, "rb"))) {
		perror(path);
		return 2;
	}
	text = slurp(f, &len);
	if (f != stdin)
		fclose(f);

	if (golf && len > 8 && memcmp(text, "/* golf:", 8) == 0) {
		char *eol = memchr(text, '\n', len), *end;
		size_t skip = eol ? (size_t)(eol - text) + 1 : len;
		/* a description right after it, the entry's tricks and how to
		   run it, is asked of entrants: it costs them nothing either */
		if (len - skip > 3 && memcmp(text + skip, "/*!", 3) == 0) {
			for (end = text + skip + 3; end + 1 < text + len; end++)
				if (end[0] == '*' && end[1] == '/')
					break;
			eol = memchr(end, '\n', (size_t)(text + len - end));
			skip = eol ? (size_t)(eol - text) + 1 : len;
		}
		memmove(text, text + skip, len - skip);
		len -= skip;
	}
	bytes = len;

	for (k = 0; k < len; k++) {
		char c = text[k];
		if (c == '\n') {
			lines++;
			col = 0;
			continue;
		}
		col = c == '\t' ? (col / 8 + 1) * 8 : col + 1;
		if (col > cols)
			cols = col;
		if (clex_isspace(c))
			continue;
		if ((c == '{' || c == '}' || c == ';')
		    && (k + 1 == len || clex_isspace(text[k + 1])))
			continue;
		ioccc++;
	}
	if (len && text[len - 1] != '\n')
		lines++;

	spliced = malloc(len + 1);
	if (!spliced) {
		perror("ctok");
		return 2;
	}
	if (len)
		memcpy(spliced, text, len);
	slen = clex_splice(spliced, len);
	clex_init(&L, spliced, slen);
	while (clex_next(&L, &t) != T_END) {
		if (t.kind == T_COMMENT)
			continue;
		tokens++;
		if (list)
			printf("%-7s %.*s\n", kindname[t.kind], (int)t.n, t.s);
	}
	if (raw)
		printf("%lu %lu %lu %lu %lu\n", (unsigned long)bytes,
		       (unsigned long)ioccc, (unsigned long)tokens,
		       (unsigned long)lines, (unsigned long)cols);
	else if (!list)
		printf("bytes %lu\nioccc %lu\ntokens %lu\nlines %lu\ncols %lu\n",
		       (unsigned long)bytes, (unsigned long)ioccc,
		       (unsigned long)tokens, (unsigned long)lines,
		       (unsigned long)cols);
	free(text);
	free(spliced);
	return 0;
}
