/* embree_cpu.c - the CPU time of Embree's build, for make bench.
 *
 *     cc -O2 -shared -fPIC -o embree_cpu.so bench/embree_cpu.c -ldl
 *     LD_PRELOAD=$PWD/embree_cpu.so embree_rays MESH.obj ...
 *
 * embree_rays (../shared/embree, an instrument we do not change) times its
 * BVH build, rtcCommitScene, by the wall clock only, and a wall clock on a
 * busy machine counts the time other processes ran.  Preloaded into it,
 * this wraps rtcCommitScene and prints to standard error, beside its own
 * figure, the CPU time the call took: the process's (every thread), and the
 * calling thread's, so that work handed to other threads would show.
 *
 *     embree_cpu: rtcCommitScene 0.0240 s CPU (process), 0.0240 s CPU (thread), 0.0312 s wall
 *
 * It needs nothing of Embree's, neither its header nor its library: the
 * real function is found at run time (dlsym, RTLD_NEXT), after this one.
 * Linux and glibc (RTLD_NEXT, the CPU-time clocks); make bench goes on with
 * the wall clock where it does not build.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double clock_s(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

void rtcCommitScene(void *scene);
void rtcCommitScene(void *scene)
{
    static void (*real)(void *);
    double p0, t0, w0;
    if (!real) {
        *(void **)&real = dlsym(RTLD_NEXT, "rtcCommitScene");
        if (!real) {
            fprintf(stderr, "embree_cpu: rtcCommitScene not found after this library\n");
            exit(1);
        }
    }
    w0 = clock_s(CLOCK_MONOTONIC), p0 = clock_s(CLOCK_PROCESS_CPUTIME_ID), t0 = clock_s(CLOCK_THREAD_CPUTIME_ID);
    real(scene);
    t0 = clock_s(CLOCK_THREAD_CPUTIME_ID) - t0, p0 = clock_s(CLOCK_PROCESS_CPUTIME_ID) - p0;
    w0 = clock_s(CLOCK_MONOTONIC) - w0;
    fprintf(stderr, "embree_cpu: rtcCommitScene %.4f s CPU (process), %.4f s CPU (thread), %.4f s wall\n", p0, t0,
            w0);
}
