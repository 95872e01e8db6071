/* Which photons an estimate counts (ray.c's counts, photon_estimate and
 * disc_estimate), on a diffuse floor by hand-placed photons: one on the
 * floor near the point counts; one as near but off the floor's plane (a
 * wall's photon in a corner) does not, nor one that took more rays than
 * the camera's side has left under -d.  Each estimate is then exactly the
 * one photon's power times f over its disc, pi r^2: the map's whole radius
 * for photon mapping (fewer photons than it takes), the 16th pilot
 * photon's distance for progressive photon mapping. */
#define main ray_main
#include "../ray.c"
#undef main
#include "report.h"

static int close_to(vec a, vec b)
{
    return fabs(a.x - b.x) <= 1e-12 * fabs(b.x) && fabs(a.y - b.y) <= 1e-12 * fabs(b.y)
           && fabs(a.z - b.z) <= 1e-12 * fabs(b.z);
}

int main(int argc, char **argv)
{
    Scene s;
    Photons ph;
    Worker wk;
    Hit h;
    Bsdf b;
    Ray r;
    vec wo = v3(0, 1, 0), from = unit(v3(1, 2, 0)), power = v3(1, 2, 3), want, got;
    real r2;
    int i;
    if (argc < 2 || !load_scene(&s, argv[1]) || !build_accel(&s, "none")) return 2;
    memset(&wk, 0, sizeof wk);
    for (i = 0; i < SHADOW_SLOTS; i++) wk.blocker[i] = -1;
    r.o = v3(0, 1, 0), r.d = v3(0, -1, 0), r.tmin = 0, r.skip = -1, r.time = 0;
    if (!nearest_hit(&s, r, &h, &wk)) return 2;
    bsdf_at(&s, &h, wo, &b);
    memset(&ph, 0, sizeof ph);
    keep_photon(&ph.global, v3(0.1, 0, 0), power, from, 2);         /* counts */
    keep_photon(&ph.global, v3(0, 0.1, 0.1), power, from, 2);       /* off the plane */
    keep_photon(&ph.global, v3(0, 0, -0.1), power, from, 9);        /* too many rays */
    build_map(&ph.global);
    want = scale(1 / ((real)PI * (real)0.25), mul(bsdf_eval(&b, wo, from), power));

    ph.r2 = 0.25;                           /* photon mapping: fewer than PHOTON_K, the whole radius */
    got = photon_estimate(&ph, &ph.global, &h, &b, wo, 3);
    report(close_to(got, want), "photon mapping's estimate counts the floor's photon alone",
           "%.6g %.6g %.6g, want %.6g %.6g %.6g", got.x, got.y, got.z, want.x, want.y, want.z);

    ph.progressive = 1, ph.shrink = 1, ph.r2 = 100;
    for (i = 0; i < PPM_FIRST; i++) {       /* the pilot: a ring of radius 1/2 round the point */
        real a = 2 * (real)PI * i / PPM_FIRST;
        keep_photon(&ph.pilot, v3(0.5 * cos(a), 0, 0.5 * sin(a)), power, from, 2);
    }
    build_map(&ph.pilot);
    r2 = disc_radius2(&ph, &h);
    want = scale(1 / ((real)PI * r2), mul(bsdf_eval(&b, wo, from), power));
    got = disc_estimate(&ph, &h, &b, wo, 3);
    report(fabs(r2 - 0.25) < 1e-6 && close_to(got, want),
           "progressive photon mapping's estimate counts the floor's photon alone, in the pilot's radius",
           "r^2 %.9g; %.6g %.6g %.6g, want %.6g %.6g %.6g", r2, got.x, got.y, got.z, want.x, want.y, want.z);
    free_photons(&ph);
    free_scene(&s);
    return failures != 0;
}
