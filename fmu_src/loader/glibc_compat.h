/* Old glibc symbol versions for the loader, so that the FMU's binary loads on Linux systems older
 * than the one it was built on (docs/fmu.md, "What a target machine needs").
 *
 * Built on glibc >= 2.34, a library that calls dlopen asks for dlopen@GLIBC_2.34 (the dl functions
 * moved into libc there), and one that calls stat asks for stat@GLIBC_2.33; on an older system the
 * host then stops with a linker error before the FMU can say anything.  The loader binds the dl
 * functions, and the pthread functions that lived in libpthread.so.0, to the versions every glibc
 * has (on older systems they resolve in libdl.so.2 and libpthread.so.0, which the build links with
 * --no-as-needed) and does not call stat at all.  The floor is glibc 2.17 (CentOS 7,
 * manylinux2014); tests/test_loader_symbols.py fails when a build asks for anything newer.
 *
 * Included first by every loader source; it does nothing where the C library is not glibc (Windows). */
#ifndef GLIBC_COMPAT_H
#define GLIBC_COMPAT_H

#if defined(__linux__)
#include <features.h> /* defines __GLIBC__ */
#endif

#if defined(__linux__) && defined(__GLIBC__)
#if defined(__x86_64__)
#define GLIBC_BASE_VERSION "GLIBC_2.2.5"
#elif defined(__aarch64__)
#define GLIBC_BASE_VERSION "GLIBC_2.17"
#endif

#ifdef GLIBC_BASE_VERSION
#define GLIBC_PIN(symbol) __asm__(".symver " #symbol "," #symbol "@" GLIBC_BASE_VERSION)
GLIBC_PIN(dlopen);
GLIBC_PIN(dlsym);
GLIBC_PIN(dlclose);
GLIBC_PIN(dlerror);
GLIBC_PIN(dladdr);
/* in libpthread.so.0 before glibc 2.34 */
GLIBC_PIN(pthread_mutex_trylock);
GLIBC_PIN(pthread_once);
#endif
#endif

#endif
