/* golf: ref=md5:61389114251af8c54260a89f79f529da in=scenes/minray.sph */
/*! minray.c reading its spheres from stdin: ./a.out <scenes/minray.sph >x.ppm
A sphere is a line of exactly 12 numbers once a # comment is cut; all other
lines are skipped; 98 spheres at most.  Made by golf/squeeze from golf/src. */
/* The readable source of golf/minray_sph.c: minray.c with its sphere table
   read from standard input in the shared format of scenes/minray.sph.
   Regenerate the card with "make golf-squeeze" after editing.
   The rest is minray.c's text, including its three portability fixes:
   ';' closes each struct member list (tcc), printf gets U.x, U.y, U.z (no
   struct through "..."), and trace reads s->color, not U, because U may be
   changed by the recursive trace calls among the same arguments. */

typedef struct { double x, y, z; } vec;

vec U, black, amb = { .02, .02, .02 };

struct sphere {
	vec cen, color;
	double rad, kd, ks, kt, kl, ir;
} *s, *best, sph[99];

yx, n;   /* n: the spheres read */
double u, b, tmin, sqrt(), tan();

double vdot(A, B) vec A, B;
{
	return A.x * B.x + A.y * B.y + A.z * B.z;
}

vec vcomb(a, A, B) double a; vec A, B;
{
	B.x += a * A.x;
	B.y += a * A.y;
	B.z += a * A.z;
	return B;
}

vec vunit(A) vec A;
{
	return vcomb(1. / sqrt(vdot(A, A)), A, black);
}

struct sphere *intersect(P, D) vec P, D;
{
	best = 0;
	tmin = 1e30;
	s = sph + n;
	while (s-- > sph)
		b = vdot(D, U = vcomb(-1., P, s->cen)),
		u = b * b - vdot(U, U) + s->rad * s->rad,
		u = u > 0 ? sqrt(u) : 1e31,
		u = b - u > 1e-7 ? b - u : b + u,
		tmin = u >= 1e-7 && u < tmin ? best = s, u : tmin;
	return best;
}

vec trace(level, P, D) vec P, D;
{
	double d, eta, e;
	vec N, color;
	struct sphere *s, *l;

	if (!level--)
		return black;
	if (s = intersect(P, D))
		;
	else
		return amb;
	color = amb;
	eta = s->ir;
	d = -vdot(D, N = vunit(vcomb(-1., P = vcomb(tmin, D, P), s->cen)));
	if (d < 0)
		N = vcomb(-1., N, black), eta = 1 / eta, d = -d;
	l = sph + n;
	while (l-- > sph)
		if ((e = l->kl * vdot(N, U = vunit(vcomb(-1., P, l->cen)))) > 0
		    && intersect(P, U) == l)
			color = vcomb(e, l->color, color);
	U = s->color;
	color.x *= U.x;
	color.y *= U.y;
	color.z *= U.z;
	e = 1 - eta * eta * (1 - d * d);
	return vcomb(s->kt,
	             e > 0 ? trace(level, P, vcomb(eta, D,
	                                           vcomb(eta * d - sqrt(e), N,
	                                                 black)))
	                   : black,
	             vcomb(s->ks, trace(level, P, vcomb(2 * d, N, D)),
	                   vcomb(s->kd, color, vcomb(s->kl, s->color, black))));
}

main()
{
	char l[999], *p;
	int k, c;
	double *d;

	/* one line a turn; an empty line leaves l empty (scanf gives 0) */
	while (*l = 0, ~scanf("%998[^\n]", l)) {
		getchar();
		l[strcspn(l, "#")] = 0;
		/* up to 12 numbers straight into the next free sphere, whose
		   members are 12 doubles in the format's order */
		for (p = l, k = 0, d = (void *)(sph + n);
		     k < 12 && sscanf(p, "%lf%n", d + k, &c) > 0; p += c)
			k++;
		/* a sphere only if nothing but blanks follows the 12th:
		   "%*s" then finds no input and sscanf gives EOF */
		n += n < 98 && k > 11 && sscanf(p, "%*s") < 0;
	}
	printf("P3\n%d %d\n255\n", 32, 32);
	while (yx < 32 * 32)
		U.x = yx % 32 - 32 / 2,
		U.z = 32 / 2 - yx++ / 32,
		U.y = 32 / 2 / tan(25 / 114.5915590261),
		U = vcomb(255., trace(3, black, vunit(U)), black),
		printf("%.0f %.0f %.0f\n", U.x, U.y, U.z);
}
