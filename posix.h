/* posix.h - first in every source of ./ray: POSIX's calls (stat, open,
 * isatty, clock_gettime, getpid, and the X/Open realpath) where the system
 * has them, RAY_POSIX then defined; elsewhere the program is plain C99 and
 * does without. */
#ifndef POSIX_H
#define POSIX_H
#if defined(__unix__) || defined(__APPLE__)
#define _POSIX_C_SOURCE 200809L
#define _XOPEN_SOURCE 700
#define RAY_POSIX
#endif
#endif
