/* Find, load and start the CPython that runs a pythonfmu FMU (see python_runtime.h). Linux only. */
#define _GNU_SOURCE
#include "glibc_compat.h"

#include "python_runtime.h"

#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <gnu/libc-version.h>
#include <limits.h>
#include <link.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <spawn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include <wchar.h>

#include "guard.h"

extern char **environ;

#define CONFIG_FILE "python.cfg" /* in resources/, written by the build */
#define QUERY_TIMEOUT_MS 20000   /* a candidate interpreter must answer within this time */
#ifndef BACKEND_NEEDS /* what the FMI library's binary asks of the system (the build measures it) */
#define BACKEND_NEEDS "a recent glibc and libstdc++"
#endif

typedef struct {
    int major, minor;
    char library[PATH_MAX];    /* the shared libpython */
    char home[PATH_MAX];       /* sys.base_prefix: where its standard library lives */
    char executable[PATH_MAX]; /* the base interpreter (may be empty) */
} python_install;

static pthread_mutex_t load_lock = PTHREAD_MUTEX_INITIALIZER;
static void *backend_handle;

/* ---------------------------------------------------------------------------------- helpers */

static void appendf(char *buffer, size_t size, const char *format, ...) {
    size_t used = strlen(buffer);
    if (used + 1 >= size) return;
    va_list args;
    va_start(args, format);
    vsnprintf(buffer + used, size - used, format, args);
    va_end(args);
}

static void parent_folder(char *path) {
    char *slash = strrchr(path, '/');
    if (slash == path) slash[1] = '\0';
    else if (slash) *slash = '\0';
}

static const char *base_name(const char *path) {
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

/* The folder of this shared library (binaries/<platform>). */
static int own_folder(char *folder, size_t size) {
    Dl_info info;
    if (!dladdr((void *)&python_runtime_load_backend, &info) || !info.dli_fname) return 0;
    if (!realpath(info.dli_fname, folder)) snprintf(folder, size, "%s", info.dli_fname);
    parent_folder(folder);
    return 1;
}

/* The first executable `name` in the folders of PATH (or `name` itself if it holds a slash). */
static int which(const char *name, char *found, size_t size) {
    if (strchr(name, '/')) {
        snprintf(found, size, "%s", name);
        return access(found, X_OK) == 0;
    }
    const char *path = getenv("PATH");
    if (!path) return 0;
    for (const char *start = path; *start;) {
        const char *end = strchr(start, ':');
        size_t length = end ? (size_t)(end - start) : strlen(start);
        snprintf(found, size, "%.*s/%s", (int)length, length ? start : ".", name);
        if (access(found, X_OK) == 0 && guard_is_file(found)) return 1;
        if (!end) break;
        start = end + 1;
    }
    return 0;
}

/* ------------------------------------------------------------------- a Python already here */

static int find_loaded_libpython(struct dl_phdr_info *info, size_t size, void *data) {
    (void)size;
    if (strncmp(base_name(info->dlpi_name), "libpython3", 10) != 0) return 0;
    snprintf((char *)data, PATH_MAX, "%s", info->dlpi_name);
    return 1;
}

/* True if the process already has a CPython whose symbols pythonfmu's library can see: the
 * interpreter of a Python host (libpython or a python executable exporting its symbols), or a
 * libpython loaded privately, which is then made global (RTLD_NOLOAD: no second copy). */
static int python_in_process(void) {
    if (dlsym(RTLD_DEFAULT, "Py_IsInitialized")) return 1;
    char loaded[PATH_MAX] = "";
    dl_iterate_phdr(find_loaded_libpython, loaded);
    return loaded[0] && dlopen(loaded, RTLD_NOW | RTLD_NOLOAD | RTLD_GLOBAL) != NULL;
}

/* ------------------------------------------------------------------------------ candidates */

/* Run `interpreter` to ask for its version, libpython, home and base executable. */
static int query_interpreter(const char *interpreter, python_install *python, char *why, size_t size) {
    static const char query[] =
        "import os, sys, sysconfig as c\n"
        "v = sys.version_info\n"
        "print(sys.implementation.name, v[0], v[1])\n"
        "print(os.path.join(c.get_config_var('LIBDIR') or '', c.get_config_var('INSTSONAME') or ''))\n"
        "print(sys.base_prefix)\n"
        "print(getattr(sys, '_base_executable', '') or sys.executable)\n";
    int pipe_fds[2];
    if (pipe2(pipe_fds, O_CLOEXEC) != 0) {
        snprintf(why, size, "cannot ask it (pipe: %s)", strerror(errno));
        return 0;
    }
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], 1);
    posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
    char *argv[] = {(char *)interpreter, "-I", "-S", "-c", (char *)query, NULL};
    pid_t pid;
    int spawned = posix_spawn(&pid, interpreter, &actions, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&actions);
    close(pipe_fds[1]);
    if (spawned != 0) {
        close(pipe_fds[0]);
        snprintf(why, size, "cannot run it (%s)", strerror(spawned));
        return 0;
    }
    char output[4 * PATH_MAX] = "";
    size_t used = 0;
    struct timespec start, now;
    clock_gettime(CLOCK_MONOTONIC, &start);
    int timed_out = 0;
    for (;;) {
        clock_gettime(CLOCK_MONOTONIC, &now);
        long waited = (now.tv_sec - start.tv_sec) * 1000 + (now.tv_nsec - start.tv_nsec) / 1000000;
        struct pollfd fd = {pipe_fds[0], POLLIN, 0};
        if (waited >= QUERY_TIMEOUT_MS || poll(&fd, 1, (int)(QUERY_TIMEOUT_MS - waited)) == 0) {
            timed_out = 1;
            break;
        }
        ssize_t got = read(pipe_fds[0], output + used, sizeof output - 1 - used);
        if (got < 0 && errno == EINTR) continue;
        if (got <= 0) break;
        used += (size_t)got;
        if (used + 1 >= sizeof output) break;
    }
    output[used] = '\0';
    close(pipe_fds[0]);
    if (timed_out) kill(pid, SIGKILL);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (timed_out) {
        snprintf(why, size, "did not answer within %d s", QUERY_TIMEOUT_MS / 1000);
        return 0;
    }
    char implementation[32] = "";
    char *line = strchr(output, '\n');
    if (sscanf(output, "%31s %d %d", implementation, &python->major, &python->minor) != 3 || !line) {
        snprintf(why, size, "did not answer as a Python does");
        return 0;
    }
    char *fields[3] = {python->library, python->home, python->executable};
    for (int k = 0; k < 3; k++) {
        char *start = line + 1, *end = strchr(start, '\n');
        if (!end) {
            snprintf(why, size, "did not answer as a Python does");
            return 0;
        }
        *end = '\0';
        snprintf(fields[k], PATH_MAX, "%s", start);
        line = end;
    }
    if (strcmp(implementation, "cpython") != 0) {
        snprintf(why, size, "is %s, not CPython", implementation);
        return 0;
    }
    return 1;
}

/* A libpython named directly: its version from the file name, its home from where it lies
 * (<home>/lib/libpython3.X.so or <home>/lib/<multiarch>/libpython3.X.so). */
static int describe_library(const char *library, python_install *python, char *why, size_t size) {
    if (sscanf(base_name(library), "libpython%d.%d", &python->major, &python->minor) != 2) {
        snprintf(why, size, "is neither a python3 interpreter nor a libpython3.X.so");
        return 0;
    }
    if (!realpath(library, python->library)) {
        snprintf(why, size, "does not exist");
        return 0;
    }
    char home[PATH_MAX], landmark[PATH_MAX + 64];
    snprintf(home, sizeof home, "%s", python->library);
    for (int up = 0; up < 3; up++) {
        parent_folder(home);
        snprintf(landmark, sizeof landmark, "%s/lib/python%d.%d/os.py", home, python->major, python->minor);
        if (up > 0 && guard_is_file(landmark)) {
            snprintf(python->home, PATH_MAX, "%s", home);
            snprintf(python->executable, PATH_MAX, "%s/bin/python%d.%d", home, python->major, python->minor);
            if (!guard_is_file(python->executable)) python->executable[0] = '\0';
            return 1;
        }
    }
    snprintf(why, size, "has no standard library beside it (lib/python%d.%d/os.py)", python->major, python->minor);
    return 0;
}

/* The interpreter recorded by the build in resources/python.cfg (key=value lines). */
static int read_recorded(const char *resources, python_install *python, char *why, size_t size) {
    char path[PATH_MAX + 32];
    snprintf(path, sizeof path, "%s/%s", resources, CONFIG_FILE);
    FILE *file = fopen(path, "r");
    if (!file) {
        snprintf(why, size, "none recorded (%s missing)", path);
        return 0;
    }
    char line[PATH_MAX + 32];
    while (fgets(line, sizeof line, file)) {
        line[strcspn(line, "\r\n")] = '\0';
        char *value = strchr(line, '=');
        if (!value || line[0] == '#') continue;
        *value++ = '\0';
        if (strcmp(line, "library") == 0) snprintf(python->library, PATH_MAX, "%s", value);
        else if (strcmp(line, "home") == 0) snprintf(python->home, PATH_MAX, "%s", value);
        else if (strcmp(line, "executable") == 0) snprintf(python->executable, PATH_MAX, "%s", value);
        else if (strcmp(line, "version") == 0) sscanf(value, "%d.%d", &python->major, &python->minor);
    }
    fclose(file);
    if (!guard_is_file(python->library) && python->executable[0] && !guard_is_file(python->executable)) {
        snprintf(why, size, "not found (%s and %s are gone)", python->executable,
                 python->library[0] ? python->library : "its libpython");
        return 0;
    }
    return 1;
}

/* Can `python` run the FMU: CPython >= 3.11 with a shared libpython and its standard library? */
static int usable(const python_install *python, char *why, size_t size) {
    char landmark[PATH_MAX + 64];
    snprintf(landmark, sizeof landmark, "%s/lib/python%d.%d/encodings/__init__.py", python->home, python->major,
             python->minor);
    if (python->major != 3 || python->minor < PYTHON_MIN_MINOR)
        snprintf(why, size, "is Python %d.%d, older than 3.%d", python->major, python->minor, PYTHON_MIN_MINOR);
    else if (!strstr(base_name(python->library), ".so") || !guard_is_file(python->library))
        snprintf(why, size, "is Python %d.%d without a shared libpython (%s missing)", python->major, python->minor,
                 python->library[0] ? python->library : "libpython3.X.so");
    else if (!guard_is_file(landmark))
        snprintf(why, size, "has no standard library at %s", python->home);
    else
        return 1;
    return 0;
}

/* ------------------------------------------------------------------------------- starting */

typedef int (*is_initialized_fn)(void);
typedef void (*initialize_ex_fn)(int);
typedef void *(*save_thread_fn)(void);
typedef void (*set_wide_fn)(const wchar_t *);
typedef wchar_t *(*decode_locale_fn)(const char *, size_t *);

/* Load `python`'s libpython with global symbols and initialise it with its own home. */
static int start_python(const python_install *python, char *why, size_t size) {
    void *library = dlopen(python->library, RTLD_NOW | RTLD_GLOBAL);
    if (!library) {
        snprintf(why, size, "cannot be loaded: %s", dlerror());
        return 0;
    }
    is_initialized_fn is_initialized = (is_initialized_fn)dlsym(library, "Py_IsInitialized");
    initialize_ex_fn initialize_ex = (initialize_ex_fn)dlsym(library, "Py_InitializeEx");
    save_thread_fn save_thread = (save_thread_fn)dlsym(library, "PyEval_SaveThread");
    decode_locale_fn decode = (decode_locale_fn)dlsym(library, "Py_DecodeLocale");
    if (!is_initialized || !initialize_ex || !save_thread || !decode) {
        snprintf(why, size, "%s is not a CPython library", python->library);
        return 0;
    }
    if (is_initialized()) return 1;
    /* Py_SetPythonHome and Py_SetProgramName (deprecated since 3.11, still in 3.14) keep their
     * arguments: decoded once, never freed. Without them (3.15+) the home goes through PYTHONHOME,
     * set only while the interpreter starts and restored at once.  The FMU needs the standard
     * library alone: no site-packages (no `site`), and the host's PYTHON* variables, meant for
     * some other Python, are ignored (flags deprecated since 3.12, where they exist). */
    set_wide_fn set_home = (set_wide_fn)dlsym(library, "Py_SetPythonHome");
    set_wide_fn set_program = (set_wide_fn)dlsym(library, "Py_SetProgramName");
    int *no_site = (int *)dlsym(library, "Py_NoSiteFlag");
    if (no_site) *no_site = 1;
    if (set_home) {
        int *ignore_environment = (int *)dlsym(library, "Py_IgnoreEnvironmentFlag");
        if (ignore_environment) *ignore_environment = 1;
        set_home(decode(python->home, NULL));
        if (set_program && python->executable[0]) set_program(decode(python->executable, NULL));
        initialize_ex(0); /* 0: no signal handlers, SIGINT and SIGPIPE stay the host's */
    } else {
        const char *old = getenv("PYTHONHOME");
        char *saved = old ? strdup(old) : NULL;
        setenv("PYTHONHOME", python->home, 1);
        initialize_ex(0);
        if (saved) setenv("PYTHONHOME", saved, 1);
        else unsetenv("PYTHONHOME");
        free(saved);
    }
    if (!is_initialized()) {
        snprintf(why, size, "did not start");
        return 0;
    }
    save_thread(); /* release the GIL: pythonfmu takes it with PyGILState_Ensure on every call */
    return 1;
}

/* Try one candidate: report in `tried`, start it if usable. */
static int try_candidate(const char *label, int described, const python_install *python, char *why, char *tried,
                         size_t tried_size) {
    if (described && usable(python, why, PATH_MAX) && start_python(python, why, PATH_MAX)) return 1;
    appendf(tried, tried_size, "%s%s %s", tried[0] ? "; " : "", label, why);
    return 0;
}

static int find_and_start_python(const char *resources, char *error, size_t error_size) {
    char tried[3 * PATH_MAX] = "", why[PATH_MAX] = "", label[PATH_MAX + 64], interpreter[PATH_MAX];
    python_install python;
    const char *override = getenv(PYTHON_OVERRIDE_VARIABLE);
    if (override && override[0]) {
        memset(&python, 0, sizeof python);
        snprintf(label, sizeof label, "%s=%s", PYTHON_OVERRIDE_VARIABLE, override);
        int described;
        if (strstr(base_name(override), "libpython")) described = describe_library(override, &python, why, sizeof why);
        else if (!which(override, interpreter, sizeof interpreter))
            described = (snprintf(why, sizeof why, "is not an executable file"), 0);
        else described = query_interpreter(interpreter, &python, why, sizeof why);
        if (try_candidate(label, described, &python, why, tried, sizeof tried)) return 1;
    } else {
        memset(&python, 0, sizeof python);
        int described = read_recorded(resources, &python, why, sizeof why);
        snprintf(label, sizeof label, "the build's Python%s%s", described ? " " : "", described ? python.executable : "");
        if (try_candidate(label, described, &python, why, tried, sizeof tried)) return 1;

        memset(&python, 0, sizeof python);
        const char *path = getenv("PATH");
        if (which("python3", interpreter, sizeof interpreter)) {
            snprintf(label, sizeof label, "python3 on PATH (%s)", interpreter);
            described = query_interpreter(interpreter, &python, why, sizeof why);
        } else {
            snprintf(label, sizeof label, "python3 on PATH (%s)", path ? path : "PATH unset");
            described = (snprintf(why, sizeof why, "not found"), 0);
        }
        if (try_candidate(label, described, &python, why, tried, sizeof tried)) return 1;
    }
    snprintf(error, error_size,
             "no usable Python to run this FMU (it needs CPython >= 3.%d with a shared libpython, standard library "
             "only): %s. Set %s to such a python3 or to its libpython3.X.so",
             PYTHON_MIN_MINOR, tried, PYTHON_OVERRIDE_VARIABLE);
    return 0;
}

/* ----------------------------------------------------------------------------------- entry */

static void *load_backend(const char *resources_uri, const char *backend_file, char *error, size_t error_size) {
    char folder[PATH_MAX], resources[PATH_MAX], backend[PATH_MAX + 64];
    if (!own_folder(folder, sizeof folder)) {
        snprintf(error, error_size, "cannot locate the FMU's binary folder");
        return NULL;
    }
    if (!resources_uri || !resources_uri[0] || !guard_uri_to_path(resources_uri, resources, sizeof resources))
        snprintf(resources, sizeof resources, "%s/../../resources", folder);
    if (!python_in_process() && !find_and_start_python(resources, error, error_size)) return NULL;
    snprintf(backend, sizeof backend, "%s/%s", folder, backend_file);
    void *handle = dlopen(backend, RTLD_NOW | RTLD_LOCAL);
    if (!handle)
        guard_format(error, error_size, "cannot load the FMI library's binary %s (it needs %s; this machine has glibc %s): %s",
                     backend_file, BACKEND_NEEDS, gnu_get_libc_version(), dlerror());
    return handle;
}

void *python_runtime_load_backend(const char *resources_uri, const char *backend_file, char *error,
                                  size_t error_size) {
    pthread_mutex_lock(&load_lock);
    if (!backend_handle) {
        /* stderr's lock is the one lock every copy of the loader in the process shares (the FMUs'
         * binaries are separate copies): two FMUs never start a Python at the same moment. */
        flockfile(stderr);
        backend_handle = load_backend(resources_uri, backend_file, error, error_size);
        funlockfile(stderr);
    }
    void *handle = backend_handle;
    pthread_mutex_unlock(&load_lock);
    return handle;
}

/* Unloading the FMU's binary unloads pythonfmu's library with it (as when it was the binary
 * itself); a Python this loader started stays loaded and running until the process ends. */
__attribute__((destructor)) static void unload_backend(void) {
    if (backend_handle) dlclose(backend_handle);
    backend_handle = NULL;
}
