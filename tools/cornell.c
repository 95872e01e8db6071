/* cornell.c: prints scenes/cornell.sph, the Cornell box from its measured data.
 *
 *     cc -O2 -o /tmp/cornell tools/cornell.c -lm && /tmp/cornell > scenes/cornell.sph
 *
 * The data are the Cornell Program of Computer Graphics' "Cornell Box Data" page,
 * http://www.graphics.cornell.edu/online/box/data.html : geometry in millimetres, the
 * camera, the reflectance spectra of the white, green and red paint (400-700 nm in
 * 4 nm steps) and the light's emission spectrum (400, 500, 600 and 700 nm).  The colour
 * matching functions are the CIE 1931 2-degree standard observer's 5 nm table (as in
 * CIE 15:2004).  sRGB is IEC 61966-2-1: its primaries and its D65 white.
 *
 * How a spectrum becomes an RGB triple:
 *   - Every spectrum is sampled at the observer's 5 nm points from 400 to 700 nm:
 *     the reflectances by linear interpolation between their 4 nm samples, the light
 *     by linear interpolation between its four samples.
 *   - XYZ = sum over those points of S(l) * (xbar, ybar, zbar)(l), divided by the sum
 *     of ybar: a flat spectrum of value 1 (illuminant E) has Y = 1.
 *   - linear sRGB = M * XYZ, with M built below from the sRGB primaries and D65.
 *   - The light's RGB is its spectrum's RGB, nothing else: its radiance in the data's
 *     own units, a warm (incandescent-looking) white.
 *   - A reflectance is seen under the box's own light L: its albedo in channel c is
 *     RGB_c(reflectance * L) / RGB_c(L).  An RGB renderer multiplies the light's RGB by
 *     the albedo, so light once reflected comes out exactly as the spectral product
 *     would; and a perfect white reflector gets albedo (1, 1, 1) (a white balance to the
 *     light).  Reflectances under D65 are printed beside them in the scene's comments.
 *
 * The mistake this avoids: reading the 700, 600 and 500 nm samples (or worse, the 500,
 * 600 and 700 nm ones) as R, G and B.  The red paint is (0.058, 0.287, 0.642) at 500,
 * 600 and 700 nm, which as (R, G, B) is a blue wall.
 *
 * C99, libc and libm only; the output is a deterministic function of the tables below. */

#include <math.h>
#include <stdio.h>

#define NOBS 61         /* observer samples: 400, 405, ..., 700 nm */
#define NREF 76         /* reflectance samples: 400, 404, ..., 700 nm */

/* CIE 1931 2-degree colour-matching functions xbar, ybar, zbar at 400 + 5i nm. */
static const double cmf[NOBS][3] = {
    {0.01431, 0.000396, 0.06785}, {0.02319, 0.00064, 0.1102},  {0.04351, 0.00121, 0.2074},
    {0.07763, 0.00218, 0.3713},   {0.13438, 0.004, 0.6456},    {0.21477, 0.0073, 1.03905},
    {0.2839, 0.0116, 1.3856},     {0.3285, 0.01684, 1.62296},  {0.34828, 0.023, 1.74706},
    {0.34806, 0.0298, 1.7826},    {0.3362, 0.038, 1.77211},    {0.3187, 0.048, 1.7441},
    {0.2908, 0.06, 1.6692},       {0.2511, 0.0739, 1.5281},    {0.19536, 0.09098, 1.28764},
    {0.1421, 0.1126, 1.0419},     {0.09564, 0.13902, 0.81295}, {0.05795, 0.1693, 0.6162},
    {0.03201, 0.20802, 0.46518},  {0.0147, 0.2586, 0.3533},    {0.0049, 0.323, 0.272},
    {0.0024, 0.4073, 0.2123},     {0.0093, 0.503, 0.1582},     {0.0291, 0.6082, 0.1117},
    {0.06327, 0.71, 0.07825},     {0.1096, 0.7932, 0.05725},   {0.1655, 0.862, 0.04216},
    {0.22575, 0.91485, 0.02984},  {0.2904, 0.954, 0.0203},     {0.3597, 0.9803, 0.0134},
    {0.43345, 0.99495, 0.00875},  {0.51205, 1.0, 0.00575},     {0.5945, 0.995, 0.0039},
    {0.6784, 0.9786, 0.00275},    {0.7621, 0.952, 0.0021},     {0.8425, 0.9154, 0.0018},
    {0.9163, 0.87, 0.00165},      {0.9786, 0.8163, 0.0014},    {1.0263, 0.757, 0.0011},
    {1.0567, 0.6949, 0.001},      {1.0622, 0.631, 0.0008},     {1.0456, 0.5668, 0.0006},
    {1.0026, 0.503, 0.00034},     {0.9384, 0.4412, 0.00024},   {0.85445, 0.381, 0.00019},
    {0.7514, 0.321, 0.0001},      {0.6424, 0.265, 0.00005},    {0.5419, 0.217, 0.00003},
    {0.4479, 0.175, 0.00002},     {0.3608, 0.1382, 0.00001},   {0.2835, 0.107, 0.0},
    {0.2187, 0.0816, 0.0},        {0.1649, 0.061, 0.0},        {0.1212, 0.04458, 0.0},
    {0.0874, 0.032, 0.0},         {0.0636, 0.0232, 0.0},       {0.04677, 0.017, 0.0},
    {0.0329, 0.01192, 0.0},       {0.0227, 0.00821, 0.0},      {0.01584, 0.005723, 0.0},
    {0.011359, 0.004102, 0.0}
};

/* The measured reflectances at 400 + 4i nm (the data page's table, by column). */
static const double white[NREF] = {
    0.343, 0.445, 0.551, 0.624, 0.665, 0.687, 0.708, 0.723, 0.715, 0.710,
    0.745, 0.758, 0.739, 0.767, 0.777, 0.765, 0.751, 0.745, 0.748, 0.729,
    0.745, 0.757, 0.753, 0.750, 0.746, 0.747, 0.735, 0.732, 0.739, 0.734,
    0.725, 0.721, 0.733, 0.725, 0.732, 0.743, 0.744, 0.748, 0.728, 0.716,
    0.733, 0.726, 0.713, 0.740, 0.754, 0.764, 0.752, 0.736, 0.734, 0.741,
    0.740, 0.732, 0.745, 0.755, 0.751, 0.744, 0.731, 0.733, 0.744, 0.731,
    0.712, 0.708, 0.729, 0.730, 0.727, 0.707, 0.703, 0.729, 0.750, 0.760,
    0.751, 0.739, 0.724, 0.730, 0.740, 0.737
};
static const double green[NREF] = {
    0.092, 0.096, 0.098, 0.097, 0.098, 0.095, 0.095, 0.097, 0.095, 0.094,
    0.097, 0.098, 0.096, 0.101, 0.103, 0.104, 0.107, 0.109, 0.112, 0.115,
    0.125, 0.140, 0.160, 0.187, 0.229, 0.285, 0.343, 0.390, 0.435, 0.464,
    0.472, 0.476, 0.481, 0.462, 0.447, 0.441, 0.426, 0.406, 0.373, 0.347,
    0.337, 0.314, 0.285, 0.277, 0.266, 0.250, 0.230, 0.207, 0.186, 0.171,
    0.160, 0.148, 0.141, 0.136, 0.130, 0.126, 0.123, 0.121, 0.122, 0.119,
    0.114, 0.115, 0.117, 0.117, 0.118, 0.120, 0.122, 0.128, 0.132, 0.139,
    0.144, 0.146, 0.150, 0.152, 0.157, 0.159
};
static const double red[NREF] = {
    0.040, 0.046, 0.048, 0.053, 0.049, 0.050, 0.053, 0.055, 0.057, 0.056,
    0.059, 0.057, 0.061, 0.061, 0.060, 0.062, 0.062, 0.062, 0.061, 0.062,
    0.060, 0.059, 0.057, 0.058, 0.058, 0.058, 0.056, 0.055, 0.056, 0.059,
    0.057, 0.055, 0.059, 0.059, 0.058, 0.059, 0.061, 0.061, 0.063, 0.063,
    0.067, 0.068, 0.072, 0.080, 0.090, 0.099, 0.124, 0.154, 0.192, 0.255,
    0.287, 0.349, 0.402, 0.443, 0.487, 0.513, 0.558, 0.584, 0.620, 0.606,
    0.609, 0.651, 0.612, 0.610, 0.650, 0.638, 0.627, 0.620, 0.630, 0.628,
    0.642, 0.639, 0.657, 0.639, 0.635, 0.642
};

/* The light's emission at 400, 500, 600 and 700 nm, in the data's (relative) units. */
static const double lamp[4] = { 0.0, 8.0, 15.6, 18.4 };

/* The light's radiance is the spectrum's RGB times this.  At 1 its luminance is 12.4,
 * about that of the (17, 12, 4) that renderers' Cornell scenes commonly give this light:
 * the same exposure, for images shown through the sRGB curve as theirs are. */
#define LIGHT_SCALE 1.0

/* CIE standard illuminant D65 at 400 + 5i nm, used only for the comparison in the
 * comments (CIE 15:2004's 5 nm table). */
static const double d65[NOBS] = {
    82.7549, 87.1204, 91.486, 92.4589, 93.4318, 90.057, 86.6823, 95.7736, 104.865,
    110.936, 117.008, 117.41, 117.812, 116.336, 114.861, 115.392, 115.923, 112.367,
    108.811, 109.082, 109.354, 108.578, 107.802, 106.296, 104.79, 106.239, 107.689,
    106.047, 104.405, 104.225, 104.046, 102.023, 100.0, 98.1671, 96.3342, 96.0611,
    95.788, 92.2368, 88.6856, 89.3459, 90.0062, 89.8026, 89.5991, 88.6489, 87.6987,
    85.4936, 83.2886, 83.4939, 83.6992, 81.863, 80.0268, 80.1207, 80.2146, 81.2462,
    82.2778, 80.281, 78.2842, 74.0027, 69.7213, 70.6652, 71.6091
};

typedef struct { double c[3]; } Rgb;

/* A reflectance table at wavelength nm (400..700), linearly interpolated. */
static double reflectance(const double *tab, double nm)
{
    double u = (nm - 400) / 4;
    int k = (int)u;
    if (k >= NREF - 1) return tab[NREF - 1];
    return tab[k] + (u - k) * (tab[k + 1] - tab[k]);
}

/* The light's emission at wavelength nm (400..700), linearly interpolated. */
static double emission(double nm)
{
    double u = (nm - 400) / 100;
    int k = (int)u;
    if (k >= 3) return lamp[3];
    return lamp[k] + (u - k) * (lamp[k + 1] - lamp[k]);
}

/* Inverse of a 3x3 matrix (by its adjugate). */
static void invert3(double a[3][3], double r[3][3])
{
    int i, j;
    double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
               - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
               + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            int i1 = (j + 1) % 3, i2 = (j + 2) % 3, j1 = (i + 1) % 3, j2 = (i + 2) % 3;
            r[i][j] = (a[i1][j1] * a[i2][j2] - a[i1][j2] * a[i2][j1]) / det;
        }
}

/* XYZ -> linear sRGB: the matrix whose inverse takes the primaries (R, G, B at
 * chromaticities (0.64, 0.33), (0.30, 0.60), (0.15, 0.06)) to XYZ with R + G + B =
 * D65 (0.3127, 0.3290) at Y = 1. */
static double xyz_to_rgb[3][3];

static void make_matrix(void)
{
    static const double xy[3][2] = { {0.64, 0.33}, {0.30, 0.60}, {0.15, 0.06} };
    const double wx = 0.3127, wy = 0.3290;
    double p[3][3], pinv[3][3], w[3], s[3], m[3][3];
    int i, j;
    for (j = 0; j < 3; j++) {               /* column j: primary j at Y = 1 */
        p[0][j] = xy[j][0] / xy[j][1];
        p[1][j] = 1;
        p[2][j] = (1 - xy[j][0] - xy[j][1]) / xy[j][1];
    }
    w[0] = wx / wy; w[1] = 1; w[2] = (1 - wx - wy) / wy;
    invert3(p, pinv);
    for (i = 0; i < 3; i++) s[i] = pinv[i][0] * w[0] + pinv[i][1] * w[1] + pinv[i][2] * w[2];
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) m[i][j] = p[i][j] * s[j];
    invert3(m, xyz_to_rgb);
}

/* Entry (i, j) of the linear sRGB -> XYZ matrix. */
static double xyz_inverse(int i, int j)
{
    double m[3][3];
    invert3(xyz_to_rgb, m);
    return m[i][j];
}

/* Linear sRGB of the spectrum refl(l) * illum(l), sampled at the observer's points;
 * refl may be NULL (1 everywhere); illum NULL means the box's light, else a table at
 * the observer's points. */
static Rgb to_rgb(const double *refl, const double *illum)
{
    double xyz[3] = { 0, 0, 0 }, ysum = 0;
    Rgb out = { { 0, 0, 0 } };
    int i, k;
    for (i = 0; i < NOBS; i++) {
        double nm = 400 + 5 * i;
        double s = (illum ? illum[i] : emission(nm)) * (refl ? reflectance(refl, nm) : 1);
        for (k = 0; k < 3; k++) xyz[k] += s * cmf[i][k];
        ysum += cmf[i][1];
    }
    for (k = 0; k < 3; k++) xyz[k] /= ysum;
    for (k = 0; k < 3; k++)
        out.c[k] = xyz_to_rgb[k][0] * xyz[0] + xyz_to_rgb[k][1] * xyz[1]
                 + xyz_to_rgb[k][2] * xyz[2];
    return out;
}

/* A reflectance's albedo under illuminant illum (see to_rgb), white-balanced to it. */
static Rgb albedo(const double *refl, const double *illum)
{
    Rgb a = to_rgb(refl, illum), w = to_rgb(NULL, illum);
    int k;
    for (k = 0; k < 3; k++) a.c[k] /= w.c[k];
    return a;
}

/* ------------------------------------------------------------------ geometry */

typedef struct { double x, y, z; } P3;

/* The data page's quads, vertices in its order (millimetres). */
static const P3 floor_q[4] =
    { {552.8, 0, 0}, {0, 0, 0}, {0, 0, 559.2}, {549.6, 0, 559.2} };
static const P3 ceiling_q[4] =
    { {556, 548.8, 0}, {556, 548.8, 559.2}, {0, 548.8, 559.2}, {0, 548.8, 0} };
static const P3 light_q[4] =
    { {343, 548.8, 227}, {343, 548.8, 332}, {213, 548.8, 332}, {213, 548.8, 227} };
static const P3 back_q[4] =
    { {549.6, 0, 559.2}, {0, 0, 559.2}, {0, 548.8, 559.2}, {556, 548.8, 559.2} };
static const P3 right_q[4] =
    { {0, 0, 559.2}, {0, 0, 0}, {0, 548.8, 0}, {0, 548.8, 559.2} };
static const P3 left_q[4] =
    { {552.8, 0, 0}, {549.6, 0, 559.2}, {556, 548.8, 559.2}, {556, 548.8, 0} };
static const P3 short_q[5][4] = {
    { {130, 165, 65}, {82, 165, 225}, {240, 165, 272}, {290, 165, 114} },
    { {290, 0, 114}, {290, 165, 114}, {240, 165, 272}, {240, 0, 272} },
    { {130, 0, 65}, {130, 165, 65}, {290, 165, 114}, {290, 0, 114} },
    { {82, 0, 225}, {82, 165, 225}, {130, 165, 65}, {130, 0, 65} },
    { {240, 0, 272}, {240, 165, 272}, {82, 165, 225}, {82, 0, 225} }
};
static const P3 tall_q[5][4] = {
    { {423, 330, 247}, {265, 330, 296}, {314, 330, 456}, {472, 330, 406} },
    { {423, 0, 247}, {423, 330, 247}, {472, 330, 406}, {472, 0, 406} },
    { {472, 0, 406}, {472, 330, 406}, {314, 330, 456}, {314, 0, 456} },
    { {314, 0, 456}, {314, 330, 456}, {265, 330, 296}, {265, 0, 296} },
    { {265, 0, 296}, {265, 330, 296}, {423, 330, 247}, {423, 0, 247} }
};

static char material[3][80];    /* "r g b kd ks kt kl ir" for white, red, green */
static char light_material[80];

static void tri(P3 a, P3 b, P3 c, const char *mat)
{
    printf("tri %g %g %g  %g %g %g  %g %g %g  %s\n",
           a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, mat);
}

static void quad(const P3 *q, const char *mat)
{
    tri(q[0], q[1], q[2], mat);
    tri(q[0], q[2], q[3], mat);
}

static void print_rgb(const char *label, Rgb a, const char *tail)
{
    printf("#   %-24s %.4f %.4f %.4f%s\n", label, a.c[0], a.c[1], a.c[2], tail);
}

int main(void)
{
    static const char *const names[3] = { "white", "red", "green" };
    const double *const spectra[3] = { white, red, green };
    const double pi = 3.14159265358979323846;
    double fov = 2 * atan(0.025 / 2 / 0.035) * 180 / pi, top;
    Rgb alb[3], lrgb;
    int i, k;

    make_matrix();
    lrgb = to_rgb(NULL, NULL);
    for (k = 0; k < 3; k++) lrgb.c[k] *= LIGHT_SCALE;
    for (i = 0; i < 3; i++) {
        alb[i] = albedo(spectra[i], NULL);
        sprintf(material[i], "%.4f %.4f %.4f  1 0 0 0 1", alb[i].c[0], alb[i].c[1], alb[i].c[2]);
    }
    top = lrgb.c[0];
    for (k = 1; k < 3; k++) if (lrgb.c[k] > top) top = lrgb.c[k];
    sprintf(light_material, "%.4f %.4f %.4f  0 0 0 %.4f 1",
            lrgb.c[0] / top, lrgb.c[1] / top, lrgb.c[2] / top, top);

    printf("# The Cornell box, from its measured data.  Made by tools/cornell.c: edit that, then\n"
           "#   cc -O2 -o /tmp/cornell tools/cornell.c -lm && /tmp/cornell > scenes/cornell.sph\n"
           "#\n"
           "# Source: Cornell Program of Computer Graphics, \"Cornell Box Data\",\n"
           "#   http://www.graphics.cornell.edu/online/box/data.html\n"
           "# Geometry: the page's vertices in millimetres, unchanged; a quad is two triangles.\n"
           "# Camera: the page's, at (278, 273, -800) looking along +z, up +y; focal length\n"
           "#   0.035 and film 0.025 x 0.025 give a field of view of 2 atan(0.0125 / 0.035) =\n"
           "#   %.4f degrees both ways.  The page's x grows to the camera's left: the red\n"
           "#   wall is at x = 556, the green one at x = 0.\n",
           fov);
    printf("# Colours: the page's spectra (reflectances 400-700 nm every 4 nm; the light at\n"
           "#   400, 500, 600 and 700 nm) sampled every 5 nm by linear interpolation and\n"
           "#   summed against the CIE 1931 2-degree observer (XYZ, normalised so that a flat\n"
           "#   spectrum of 1 has Y = 1), then XYZ -> linear sRGB (IEC 61966-2-1 primaries,\n"
           "#   D65 white).  A reflectance is seen under the box's own light L, white-balanced\n"
           "#   to it: albedo_c = RGB_c(reflectance x L) / RGB_c(L).  So light reflected once\n"
           "#   comes out as the spectral product would, and a perfect white would be (1, 1, 1).\n"
           "# Albedos (kd 1, so these are the Lambertian albedos):\n");
    for (i = 0; i < 3; i++) print_rgb(names[i], alb[i], "");
    printf("#   for comparison, under D65:\n");
    for (i = 0; i < 3; i++) {
        char label[32];
        sprintf(label, "%s", names[i]);
        print_rgb(label, albedo(spectra[i], d65), "");
    }
    {
        Rgb e = to_rgb(NULL, NULL);     /* unscaled, for its chromaticity */
        double x, y, X = 0, Y = 0, Z = 0, n;
        for (k = 0; k < 3; k++) {
            X += xyz_inverse(0, k) * e.c[k];
            Y += xyz_inverse(1, k) * e.c[k];
            Z += xyz_inverse(2, k) * e.c[k];
        }
        x = X / (X + Y + Z); y = Y / (X + Y + Z);
        n = (x - 0.3320) / (0.1858 - y);            /* McCamy's approximation to the CCT */
        printf("# Light: the emission spectrum's linear sRGB, in the data's units times %g:\n",
               LIGHT_SCALE);
        print_rgb("radiance kl * colour", lrgb, "");
        printf("#   chromaticity x, y = %.3f, %.3f: a warm white of about %.0f K.  Its luminance,\n"
               "#   Y = %.2f, is about that of the (17, 12, 4) common in renderers' Cornell\n"
               "#   scenes (Mitsuba's is (18.4, 11.0, 2.75)), which expose well at that through\n"
               "#   the sRGB curve.  Written as colour = radiance / its largest channel and\n"
               "#   kl = that channel.  kd 0: what the lamp reflects is negligible beside what\n"
               "#   it emits.\n",
               x, y, floor((449 * n * n * n + 3525 * n * n + 6823.3 * n + 5520.33) / 50 + 0.5) * 50,
               0.2126 * lrgb.c[0] + 0.7152 * lrgb.c[1] + 0.0722 * lrgb.c[2]);
    }
    printf("# The light lies in the ceiling's plane, y = 548.8, in a hole cut out of the ceiling\n"
           "# (eight triangles around it) so that no two surfaces overlap.  It is one-sided\n"
           "# (`sided 1`), its front facing down into the box: a lamp emits only into the room.\n"
           "# Everything else is two-sided, as a wall is Lambertian on whichever side is seen.\n"
           "# Square image as the film is.  Path traced (`integrator path`; --whitted for\n"
           "# Whitted's renderer, which shows the lamp but not its light), 256 samples a\n"
           "# pixel; paths end by Russian roulette, without a bound on their length.  No\n"
           "# ambient and no point lights (those are Whitted's): the lamp is the only light.\n"
           "\n");

    printf("size 512 512\n"
           "integrator path\n"
           "samples 256\n"
           "ambient 0 0 0\n"
           "background 0 0 0\n"
           "camera 278 273 -800  278 273 0  0 1 0  %.4f\n", fov);

    printf("\n# floor (white)\n");
    quad(floor_q, material[0]);
    printf("# ceiling (white), around the light's hole: corner i of the ceiling and of the hole\n"
           "# go round in the same order, and each side is a trapezoid of two triangles\n");
    for (i = 0; i < 4; i++) {
        int j = (i + 1) % 4;
        tri(ceiling_q[i], ceiling_q[j], light_q[j], material[0]);
        tri(ceiling_q[i], light_q[j], light_q[i], material[0]);
    }
    printf("# back wall (white)\n");
    quad(back_q, material[0]);
    printf("# left wall (red), as the camera sees it; its four corners are not quite coplanar\n");
    quad(left_q, material[1]);
    printf("# right wall (green)\n");
    quad(right_q, material[2]);
    printf("# short block (white): top and four sides\n");
    for (i = 0; i < 5; i++) quad(short_q[i], material[0]);
    printf("# tall block (white): top and four sides\n");
    for (i = 0; i < 5; i++) quad(tall_q[i], material[0]);
    printf("# the light, 130 x 105 mm; counter-clockwise seen from below, so its front faces -y\n"
           "sided 1\n");
    quad(light_q, light_material);
    printf("sided 2\n");
    return 0;
}
