/* The one place where the loader differs between POSIX (Linux) and Windows: locks, files and paths, the
 * loader's own folder, the environment, shared libraries, a CPython already in the process, and running a
 * program to read its answer.  Every other source of the loader is the same on both; only this header and
 * platform.c know `_WIN32` (as modelica/Reference-FMUs keeps it to a few lines).
 *
 * Paths cross this interface as UTF-8 on both platforms: the FMI strings are UTF-8, and on Windows every
 * call that takes a path converts it to UTF-16 and uses the system's wide ("W") functions, so a folder
 * with any name works whatever the code page. */
#ifndef PLATFORM_H
#define PLATFORM_H

#include <stddef.h>
#include <stdio.h>

#define PLATFORM_PATH_MAX 4096 /* the longest path the loader handles, in UTF-8 bytes with its NUL */

#ifdef _WIN32
typedef struct {
    void *opaque; /* an SRWLOCK: one pointer, zero when unlocked */
} platform_mutex;
#define PLATFORM_MUTEX_INIT {0}
#define PLATFORM_SEPARATOR "\\" /* what the loader joins paths with (every call takes '/' too) */
#else
#define PLATFORM_SEPARATOR "/"
#include <pthread.h>
typedef pthread_mutex_t platform_mutex;
#define PLATFORM_MUTEX_INIT PTHREAD_MUTEX_INITIALIZER
#endif

/* ---------------------------------------------------------------------------------- locks */

void platform_lock(platform_mutex *mutex);
void platform_unlock(platform_mutex *mutex);
/* The one lock every copy of the loader in the process shares (two FMUs' binaries, each with its own
 * statics): held while a Python is started, so that one starts at a time. */
void platform_lock_process(void);
void platform_unlock_process(void);

/* -------------------------------------------------------------------------- files, paths */

int platform_is_file(const char *path);      /* a readable file that is not a folder */
int platform_is_directory(const char *path); /* a folder that can be opened */
FILE *platform_open_text(const char *path);  /* opened for reading, not inherited by child processes */
/* A file URI's path part as a path of this system, in place (Windows: "/C:/x" is "C:/x"). */
void platform_uri_path(char *path);
int platform_is_separator(char c); /* '/', and on Windows '\\' too */
/* `path` cut at its last separator, in place: its folder ("/a/b" is "/a", "/a" is "/"). */
void platform_parent_folder(char *path);
/* The folder of the loader's own binary (binaries/<platform>/ in the extracted FMU); 0 if unknown. */
int platform_own_folder(char *folder, size_t size);
/* The environment variable `name` as UTF-8 in `buffer`; NULL if it is unset or does not fit. */
const char *platform_getenv(const char *name, char *buffer, size_t size);

/* ------------------------------------------------------------------------------ libraries */

/* Load the shared library `path` privately (RTLD_LOCAL; Windows: its own folder searched for the DLLs it
 * needs), or NULL and why. */
void *platform_load(const char *path, char *why, size_t size);
/* Make a library loaded by platform_load global, for the extension modules that find libpython's symbols
 * there (POSIX: RTLD_NOLOAD | RTLD_GLOBAL, the same copy; Windows has no global scope: nothing to do).
 * Returns the global handle to give back with platform_unload if starting fails, or NULL and why. */
void *platform_make_global(const char *path, void *library, char *why, size_t size);
void *platform_symbol(void *library, const char *name);
void platform_unload(void *library);
/* A CPython already in the process (a Python host's interpreter, or one another FMU started): the handle
 * to find its functions with, and the file it is in (a libpython, or a python executable that exports
 * them).  0 if there is none. */
int platform_loaded_python(void **library, char *path, size_t size);

/* ----------------------------------------------------------------------------------- fork */

/* Run `prepare` in the thread that calls fork() just before it, `parent` and `child` just after it in each
 * process (POSIX pthread_atfork; the handlers go when this library is unloaded).  1 if registered.  Windows has
 * no fork: nothing to do (1). */
int platform_at_fork(void (*prepare)(void), void (*parent)(void), void (*child)(void));
/* Keep this library in the process until it ends (POSIX RTLD_NODELETE; Windows: nothing), for the copy of the
 * loader that started the process's Python: its fork handlers must outlive an unload of the FMU. */
void platform_pin_self(void);
/* The calling thread, as a number no other live thread of the process has. */
unsigned long platform_thread_self(void);

/* ------------------------------------------------------------------------------- programs */

/* The first executable file `name` in the folders of PATH, or `name` itself if it holds a separator. */
int platform_which(const char *name, char *found, size_t size);
/* Run `argv` (argv[0] the program's path) with stdin and stderr on the null device and no signal
 * blocked, in a process group of its own that is killed whole when it ends or after `timeout_ms`, and
 * read what it writes to stdout into `output` (NUL-terminated).  Returns 1 if it exited with status 0,
 * else 0 and why.  (POSIX; on Windows the loader never runs a program: 0.) */
int platform_run(char *const argv[], char *output, size_t size, int timeout_ms, char *why, size_t why_size);

#endif
