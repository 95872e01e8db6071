/* clex.h: the C99 preprocessing-token lexer shared by ctok.c and squeeze.c.
   One lexer for both, so the squeezer joins tokens exactly where the counter
   sees them apart, and a squeezed card counts the same as its source.

   The lexer reads text that has been through translation phase 2 (every
   backslash-newline removed, see clex_splice) and returns the tokens of
   phase 3: identifiers (keywords included), pp-numbers, character constants,
   string literals, header names, punctuators and stray characters.  Comments
   come back as tokens of their own (T_COMMENT) because the squeezer keeps
   some of them and must not glue "/" to "*" or "/"; counters skip them.
   Only static functions: each tool includes this once. */
#include <stddef.h>
#include <string.h>

enum { T_END, T_IDENT, T_NUMBER, T_CHAR, T_STRING, T_HEADER, T_PUNCT,
       T_OTHER, T_COMMENT };

struct ctoken {
	const char *s;  /* the token's spelling, not NUL-terminated */
	size_t n;
	int kind;
	int space;      /* whitespace or a comment came just before it */
	int nl;         /* a newline (or the start of the text) came before it */
	int dir;        /* it belongs to a preprocessing directive */
	int dirstart;   /* it is the '#' that opens a directive */
};

struct clexer {
	const char *p, *end;
	int nl;         /* no token yet on the current line */
	int dir;        /* inside a directive: ends at the next newline */
	int dirtok;     /* tokens so far in the directive, to spot #include */
	int include;    /* the directive is #include: '<' opens a header name */
};

static void clex_init(struct clexer *L, const char *s, size_t n)
{
	L->p = s;
	L->end = s + n;
	L->nl = 1;
	L->dir = L->dirtok = L->include = 0;
}

/* Translation phase 2, in place: drop each backslash-newline (a CR before
   the newline too, for files written on DOS).  Returns the new length. */
static size_t clex_splice(char *s, size_t n)
{
	size_t i = 0, o = 0;
	while (i < n) {
		if (s[i] == '\\' && i + 1 < n && s[i + 1] == '\n') {
			i += 2;
		} else if (s[i] == '\\' && i + 2 < n && s[i + 1] == '\r'
		           && s[i + 2] == '\n') {
			i += 3;
		} else {
			s[o++] = s[i++];
		}
	}
	return o;
}

static int clex_isid(int c)
{
	/* '$' and bytes above 127 (UTF-8) are identifier characters for gcc
	   and clang; counting them as such keeps "a$b" one token. */
	return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'
	       || c == '$' || (c >= '0' && c <= '9') || (unsigned char)c > 127;
}

static int clex_isdigit(int c) { return c >= '0' && c <= '9'; }

/* The punctuators of C99 6.4.6, longest first so the first match is the
   longest one (the "maximal munch" rule of 6.4p4). */
static const char *const clex_punct[] = {
	"%:%:", "...", "<<=", ">>=",
	"->", "++", "--", "<<", ">>", "<=", ">=", "==", "!=", "&&", "||",
	"*=", "/=", "%=", "+=", "-=", "&=", "^=", "|=", "##",
	"<:", ":>", "<%", "%>", "%:",
	"[", "]", "(", ")", "{", "}", ".", "&", "*", "+", "-", "~", "!",
	"/", "%", "<", ">", "^", "|", "?", ":", ";", "=", ",", "#", NULL
};

/* Scan a quoted literal starting at the opening quote q; an unterminated
   one stops at the end of the line, as a compiler would complain there. */
static const char *clex_quoted(const char *q, const char *end)
{
	char close = *q++;
	while (q < end && *q != close && *q != '\n') {
		if (*q == '\\' && q + 1 < end && q[1] != '\n')
			q++;
		q++;
	}
	return q < end && *q == close ? q + 1 : q;
}

/* Length of the token at s (at most end), and its kind.  Used by the
   lexer and, on its own, by the squeezer to ask "would these two tokens,
   written side by side, still lex as the same first token?" */
static size_t clex_one(const char *s, const char *end, int header, int *kind)
{
	const char *q = s;
	int i;
	size_t n;
	if (s >= end) {
		*kind = T_END;
		return 0;
	}
	if (*s == '/' && s + 1 < end && s[1] == '*') {
		q = s + 2;
		while (q + 1 < end && !(q[0] == '*' && q[1] == '/'))
			q++;
		*kind = T_COMMENT;
		return (size_t)((q + 1 < end ? q + 2 : end) - s);
	}
	if (*s == '/' && s + 1 < end && s[1] == '/') {
		while (q < end && *q != '\n')
			q++;
		*kind = T_COMMENT;
		return (size_t)(q - s);
	}
	if (header && *s == '<') {
		q = s + 1;
		while (q < end && *q != '>' && *q != '\n')
			q++;
		if (q < end && *q == '>') {
			*kind = T_HEADER;
			return (size_t)(q + 1 - s);
		}
	}
	if (clex_isdigit(*s) || (*s == '.' && s + 1 < end && clex_isdigit(s[1]))) {
		/* pp-number (6.4.8): digits, letters, '_', '.', and a sign right
		   after e, E, p or P; so 0x1e+1 is one (invalid) token. */
		q = s + 1;
		while (q < end) {
			if ((*q == '+' || *q == '-') && (q[-1] == 'e' || q[-1] == 'E'
			    || q[-1] == 'p' || q[-1] == 'P'))
				q++;
			else if (clex_isid(*q) || *q == '.')
				q++;
			else
				break;
		}
		*kind = T_NUMBER;
		return (size_t)(q - s);
	}
	if (clex_isid(*s)) {
		while (q < end && clex_isid(*q))
			q++;
		n = (size_t)(q - s);
		/* L"", u"", U"", u8"" and L'', u'', U'' are one literal each */
		if (q < end && (*q == '"' || *q == '\'')
		    && ((n == 1 && (*s == 'L' || *s == 'u' || *s == 'U'))
		        || (n == 2 && s[0] == 'u' && s[1] == '8' && *q == '"'))) {
			*kind = *q == '"' ? T_STRING : T_CHAR;
			return (size_t)(clex_quoted(q, end) - s);
		}
		*kind = T_IDENT;
		return n;
	}
	if (*s == '"' || *s == '\'') {
		*kind = *s == '"' ? T_STRING : T_CHAR;
		return (size_t)(clex_quoted(s, end) - s);
	}
	for (i = 0; clex_punct[i]; i++) {
		n = strlen(clex_punct[i]);
		if ((size_t)(end - s) >= n && memcmp(s, clex_punct[i], n) == 0) {
			*kind = T_PUNCT;
			return n;
		}
	}
	*kind = T_OTHER;
	return 1;
}

static int clex_isspace(int c)
{
	return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f'
	       || c == '\v';
}

/* The next token, comments included.  Returns its kind (T_END at the end). */
static int clex_next(struct clexer *L, struct ctoken *t)
{
	int sp = 0;
	while (L->p < L->end && clex_isspace(*L->p)) {
		if (*L->p == '\n') {
			L->nl = 1;
			L->dir = 0;
		}
		sp = 1;
		L->p++;
	}
	t->space = sp;
	t->nl = L->nl;
	t->dirstart = 0;
	if (L->p >= L->end) {
		t->s = L->p;
		t->n = 0;
		t->dir = 0;
		return t->kind = T_END;
	}
	t->s = L->p;
	t->n = clex_one(L->p, L->end, L->dir && L->include, &t->kind);
	L->p += t->n;
	if (t->kind == T_COMMENT) {
		/* a comment is one space (phase 3); a // comment runs to the
		   newline, which the loop above still sees */
		t->dir = L->dir;
		return t->kind;
	}
	if (L->nl && t->kind == T_PUNCT && ((t->n == 1 && *t->s == '#')
	    || (t->n == 2 && memcmp(t->s, "%:", 2) == 0))) {
		L->dir = 1;
		L->dirtok = 0;
		L->include = 0;
		t->dirstart = 1;
	}
	if (L->dir) {
		L->dirtok++;
		if (L->dirtok == 2)
			L->include = t->kind == T_IDENT && t->n == 7
			             && memcmp(t->s, "include", 7) == 0;
	}
	t->dir = L->dir;
	L->nl = 0;
	return t->kind;
}
