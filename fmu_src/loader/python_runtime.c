/* Find, load and start the CPython that runs the FMU's Python side (see python_runtime.h). Linux only. */
#define _GNU_SOURCE
#include "glibc_compat.h"

#include "python_runtime.h"

#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
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
#ifndef QUERY_TIMEOUT_MS /* the tests compile it smaller (-DQUERY_TIMEOUT_MS=2000), not to wait 20 s */
#define QUERY_TIMEOUT_MS 20000 /* a candidate interpreter must answer within this time */
#endif
#define WHY_SIZE 1024

typedef struct {
    int major, minor;
    char library[PATH_MAX];    /* the shared libpython */
    char home[PATH_MAX];       /* sys.base_prefix: where its standard library lives */
    char executable[PATH_MAX]; /* the base interpreter (may be empty) */
} python_install;

static pthread_mutex_t load_lock = PTHREAD_MUTEX_INITIALIZER;
static python_api api;
static int api_ready;
static char failure[2048];       /* why the last search failed ("" if none failed) */
static char failure_override[PATH_MAX + 1]; /* DOUBLE_PENDULUM_FMU_PYTHON at that search */

/* ---------------------------------------------------------------------------------- helpers */

/* snprintf that says whether everything fit (a path cut short is never used). */
static int fits(char *buffer, size_t size, const char *format, ...) __attribute__((format(printf, 3, 4)));
static int fits(char *buffer, size_t size, const char *format, ...) {
    va_list args;
    va_start(args, format);
    int n = vsnprintf(buffer, size, format, args);
    va_end(args);
    return n >= 0 && (size_t)n < size;
}

static void appendf(char *buffer, size_t size, const char *format, ...) __attribute__((format(printf, 3, 4)));
static void appendf(char *buffer, size_t size, const char *format, ...) {
    size_t used = strlen(buffer);
    if (used + 1 >= size) return;
    va_list args;
    va_start(args, format);
    char part[WHY_SIZE + PATH_MAX];
    int n = vsnprintf(part, sizeof part, format, args);
    va_end(args);
    if (n > 0) guard_format(buffer + used, size - used, "%s", part);
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

/* The first executable `name` in the folders of PATH (or `name` itself if it holds a slash). */
static int which(const char *name, char *found, size_t size) {
    if (strchr(name, '/')) return fits(found, size, "%s", name) && access(found, X_OK) == 0;
    const char *path = getenv("PATH");
    if (!path) return 0;
    for (const char *start = path; *start;) {
        const char *end = strchr(start, ':');
        size_t length = end ? (size_t)(end - start) : strlen(start);
        if (fits(found, size, "%.*s/%s", (int)length, length ? start : ".", name) && access(found, X_OK) == 0 &&
            guard_is_file(found))
            return 1;
        if (!end) break;
        start = end + 1;
    }
    return 0;
}

/* ------------------------------------------------------------------- a Python already here */

static int find_loaded_libpython(struct dl_phdr_info *info, size_t size, void *data) {
    (void)size;
    if (strncmp(base_name(info->dlpi_name), "libpython3", 10) != 0) return 0;
    return fits((char *)data, PATH_MAX, "%s", info->dlpi_name);
}

/* True if the process already has an initialised CPython whose symbols the loader can find: the
 * interpreter of a Python host (libpython or a python executable exporting its symbols), or a
 * libpython loaded privately, which is then made global (RTLD_NOLOAD: no second copy). */
static int python_in_process(void) {
    int (*initialized)(void) = (int (*)(void))dlsym(RTLD_DEFAULT, "Py_IsInitialized");
    if (!initialized) {
        char loaded[PATH_MAX] = "";
        dl_iterate_phdr(find_loaded_libpython, loaded);
        if (!loaded[0] || !dlopen(loaded, RTLD_NOW | RTLD_NOLOAD | RTLD_GLOBAL)) return 0;
        initialized = (int (*)(void))dlsym(RTLD_DEFAULT, "Py_IsInitialized");
    }
    return initialized && initialized();
}

/* ------------------------------------------------------------------------------ candidates */

/* Read what the child writes to `fd` until it closes it or `deadline` (CLOCK_MONOTONIC ms) passes. */
static int read_until(int fd, char *output, size_t size, long deadline, char *why, size_t why_size) {
    size_t used = 0;
    for (;;) {
        struct timespec now;
        clock_gettime(CLOCK_MONOTONIC, &now);
        long left = deadline - (now.tv_sec * 1000L + now.tv_nsec / 1000000L);
        if (left <= 0) {
            guard_format(why, why_size, "did not answer within %d s", QUERY_TIMEOUT_MS / 1000);
            return 0;
        }
        struct pollfd ready = {fd, POLLIN, 0};
        int polled = poll(&ready, 1, (int)left);
        if (polled < 0 && errno == EINTR) continue;
        if (polled < 0) {
            guard_format(why, why_size, "cannot be read from (poll: %s)", strerror(errno));
            return 0;
        }
        if (polled == 0) continue; /* the deadline check above ends it */
        ssize_t got = read(fd, output + used, size - 1 - used);
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) {
            guard_format(why, why_size, "cannot be read from (read: %s)", strerror(errno));
            return 0;
        }
        if (got == 0) break;
        used += (size_t)got;
        if (used + 1 >= size) break;
    }
    output[used] = '\0';
    return 1;
}

/* Run `interpreter` to ask for its version, libpython, home and base executable.  It runs in a process
 * group of its own, with no signal blocked, which is killed whole when it is done (a python3 that is a
 * shell script leaves no child behind). */
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
        guard_format(why, size, "cannot ask it (pipe: %s)", strerror(errno));
        return 0;
    }
    posix_spawn_file_actions_t actions;
    posix_spawnattr_t attributes;
    sigset_t none;
    sigemptyset(&none);
    int failed = posix_spawn_file_actions_init(&actions);
    if (!failed) failed = posix_spawnattr_init(&attributes);
    if (!failed) failed = posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    if (!failed) failed = posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], 1);
    if (!failed) failed = posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
    if (!failed) failed = posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK);
    if (!failed) failed = posix_spawnattr_setpgroup(&attributes, 0);
    if (!failed) failed = posix_spawnattr_setsigmask(&attributes, &none);
    char *argv[] = {(char *)interpreter, "-I", "-S", "-c", (char *)query, NULL};
    pid_t pid = -1;
    if (!failed) failed = posix_spawn(&pid, interpreter, &actions, &attributes, argv, environ);
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attributes);
    close(pipe_fds[1]);
    if (failed) {
        close(pipe_fds[0]);
        guard_format(why, size, "cannot run it (%s)", strerror(failed));
        return 0;
    }
    char output[4 * PATH_MAX];
    struct timespec start;
    clock_gettime(CLOCK_MONOTONIC, &start);
    int answered = read_until(pipe_fds[0], output, sizeof output,
                              start.tv_sec * 1000L + start.tv_nsec / 1000000L + QUERY_TIMEOUT_MS, why, size);
    close(pipe_fds[0]);
    kill(-pid, SIGKILL); /* the group: whatever it started and left (the leader itself may have ended) */
    int status = 0;
    pid_t waited;
    while ((waited = waitpid(pid, &status, 0)) < 0 && errno == EINTR) {
    }
    if (!answered) return 0;
    /* waitpid fails (ECHILD) where the host ignores SIGCHLD or reaps every child itself: the answer stands */
    if (waited == pid && WIFEXITED(status) && WEXITSTATUS(status) != 0) {
        guard_format(why, size, "ended with exit status %d", WEXITSTATUS(status));
        return 0;
    }
    char implementation[32] = "";
    char *line = strchr(output, '\n');
    if (!line || sscanf(output, "%31s %d %d", implementation, &python->major, &python->minor) != 3) {
        guard_format(why, size, "did not answer as a Python does");
        return 0;
    }
    char *fields[3] = {python->library, python->home, python->executable};
    for (int k = 0; k < 3; k++) {
        char *begin = line + 1, *end = strchr(begin, '\n');
        if (!end) {
            guard_format(why, size, "did not answer as a Python does");
            return 0;
        }
        *end = '\0';
        if (!fits(fields[k], PATH_MAX, "%s", begin)) {
            guard_format(why, size, "answered with a path longer than %d bytes", PATH_MAX - 1);
            return 0;
        }
        line = end;
    }
    if (strcmp(implementation, "cpython") != 0) {
        guard_format(why, size, "is %s, not CPython", implementation);
        return 0;
    }
    return 1;
}

/* A libpython named directly: its version from the file name, its home from where it lies
 * (<home>/lib/libpython3.X.so or <home>/lib/<multiarch>/libpython3.X.so). */
static int describe_library(const char *library, python_install *python, char *why, size_t size) {
    if (sscanf(base_name(library), "libpython%d.%d", &python->major, &python->minor) != 2) {
        guard_format(why, size, "is neither a python3 interpreter nor a libpython3.X.so");
        return 0;
    }
    if (!realpath(library, python->library)) {
        guard_format(why, size, "does not exist");
        return 0;
    }
    char home[PATH_MAX], landmark[PATH_MAX];
    memcpy(home, python->library, sizeof home);
    for (int up = 0; up < 3; up++) {
        parent_folder(home);
        if (up > 0 && fits(landmark, sizeof landmark, "%s/lib/python%d.%d/os.py", home, python->major, python->minor) &&
            guard_is_file(landmark)) {
            memcpy(python->home, home, sizeof home);
            if (!fits(python->executable, PATH_MAX, "%s/bin/python%d.%d", home, python->major, python->minor) ||
                !guard_is_file(python->executable))
                python->executable[0] = '\0';
            return 1;
        }
    }
    guard_format(why, size, "has no standard library beside it (lib/python%d.%d/os.py)", python->major, python->minor);
    return 0;
}

/* The interpreter recorded by the build in resources/python.cfg (key=value lines). */
static int read_recorded(const char *resources, python_install *python, char *why, size_t size) {
    char path[PATH_MAX];
    if (!fits(path, sizeof path, "%s/%s", resources, CONFIG_FILE)) {
        guard_format(why, size, "none recorded (the resources folder's path is too long)");
        return 0;
    }
    FILE *file = fopen(path, "re");
    if (!file) {
        guard_format(why, size, "none recorded (%s missing)", path);
        return 0;
    }
    char line[PATH_MAX + 32];
    int complete = 1;
    while (fgets(line, sizeof line, file)) {
        line[strcspn(line, "\r\n")] = '\0';
        char *value = strchr(line, '=');
        if (!value || line[0] == '#') continue;
        *value++ = '\0';
        if (strcmp(line, "library") == 0) complete &= fits(python->library, PATH_MAX, "%s", value);
        else if (strcmp(line, "home") == 0) complete &= fits(python->home, PATH_MAX, "%s", value);
        else if (strcmp(line, "executable") == 0) complete &= fits(python->executable, PATH_MAX, "%s", value);
        else if (strcmp(line, "version") == 0) complete &= sscanf(value, "%d.%d", &python->major, &python->minor) == 2;
    }
    fclose(file);
    if (!complete) {
        guard_format(why, size, "recorded in %s, which is malformed", path);
        return 0;
    }
    if (!guard_is_file(python->library) && python->executable[0] && !guard_is_file(python->executable)) {
        guard_format(why, size, "not found (%s and %s are gone)", python->executable,
                     python->library[0] ? python->library : "its libpython");
        return 0;
    }
    return 1;
}

/* Can `python` run the FMU: CPython >= 3.11 with a shared libpython and its standard library? */
static int usable(const python_install *python, char *why, size_t size) {
    char landmark[PATH_MAX];
    if (python->major != 3 || python->minor < PYTHON_MIN_MINOR)
        guard_format(why, size, "is Python %d.%d, older than 3.%d", python->major, python->minor, PYTHON_MIN_MINOR);
    else if (!strstr(base_name(python->library), ".so") || !guard_is_file(python->library))
        guard_format(why, size, "is Python %d.%d without a shared libpython (%s missing)", python->major,
                     python->minor, python->library[0] ? python->library : "libpython3.X.so");
    else if (!fits(landmark, sizeof landmark, "%s/lib/python%d.%d/encodings/__init__.py", python->home,
                   python->major, python->minor) ||
             !guard_is_file(landmark))
        guard_format(why, size, "has no standard library at %s", python->home);
    else
        return 1;
    return 0;
}

/* ------------------------------------------------------------------------------- starting */

/* CPython's PyStatus and PyPreConfig, as 3.11 to 3.13 lay them out on Linux (Include/cpython/initconfig.h;
 * checked against those headers), with room to spare behind: PyPreConfig_InitIsolatedConfig fills it. */
typedef struct {
    int type; /* 0 OK, 1 error, 2 exit */
    const char *func, *err_msg;
    int exitcode;
} py_status;
typedef struct {
    int config_init, parse_argv, isolated, use_environment, configure_locale, coerce_c_locale,
        coerce_c_locale_warn, utf8_mode, dev_mode, allocator;
    int spare[32];
} py_pre_config;

typedef int (*is_initialized_fn)(void);
typedef void (*initialize_ex_fn)(int);
typedef void *(*save_thread_fn)(void);
typedef void (*set_wide_fn)(const wchar_t *);
typedef wchar_t *(*decode_locale_fn)(const char *, size_t *);
typedef void (*pre_config_init_fn)(py_pre_config *);
typedef py_status (*pre_initialize_fn)(const py_pre_config *);
typedef void *(*init_config_create_fn)(void);
typedef int (*init_config_set_int_fn)(void *, const char *, long long);
typedef int (*init_config_set_str_fn)(void *, const char *, const char *);
typedef int (*initialize_from_fn)(void *);
typedef int (*init_config_error_fn)(void *, const char **);
typedef void (*init_config_free_fn)(void *);

#define SYMBOL(library, type, name) ((type)dlsym(library, name))

/* CPython 3.14 and newer (PEP 741): the whole configuration by name, nothing of its layout assumed. */
static int start_by_init_config(void *library, const python_install *python, char *why, size_t size) {
    init_config_create_fn create = SYMBOL(library, init_config_create_fn, "PyInitConfig_Create");
    init_config_set_int_fn set_int = SYMBOL(library, init_config_set_int_fn, "PyInitConfig_SetInt");
    init_config_set_str_fn set_str = SYMBOL(library, init_config_set_str_fn, "PyInitConfig_SetStr");
    initialize_from_fn initialize = SYMBOL(library, initialize_from_fn, "Py_InitializeFromInitConfig");
    init_config_error_fn get_error = SYMBOL(library, init_config_error_fn, "PyInitConfig_GetError");
    init_config_free_fn release = SYMBOL(library, init_config_free_fn, "PyInitConfig_Free");
    void *config = create ? create() : NULL;
    if (!config || !set_int || !set_str || !initialize || !get_error || !release) {
        guard_format(why, size, "%s offers no way to start it without changing the host", python->library);
        if (config && release) release(config);
        return 0;
    }
    static const char *const zero[] = {"configure_locale", "install_signal_handlers", "site_import",
                                       "use_environment", "user_site_directory", "parse_argv"};
    int failed = set_int(config, "utf8_mode", 1) || set_int(config, "isolated", 1);
    for (size_t k = 0; !failed && k < sizeof zero / sizeof *zero; k++) failed = set_int(config, zero[k], 0);
    if (!failed) failed = set_str(config, "home", python->home);
    if (!failed && python->executable[0]) failed = set_str(config, "program_name", python->executable);
    if (!failed) failed = initialize(config);
    const char *message = NULL;
    if (failed && get_error(config, &message) == 0) message = NULL;
    if (failed) guard_format(why, size, "did not start (%s)", message ? message : "no reason given");
    release(config);
    return !failed;
}

/* CPython 3.11 to 3.13: pre-initialised (locale, UTF-8 mode) by PyPreConfig, then the legacy calls. */
static int start_by_legacy_calls(void *library, const python_install *python, char *why, size_t size) {
    pre_config_init_fn pre_init = SYMBOL(library, pre_config_init_fn, "PyPreConfig_InitIsolatedConfig");
    pre_initialize_fn pre_initialize = SYMBOL(library, pre_initialize_fn, "Py_PreInitialize");
    initialize_ex_fn initialize_ex = SYMBOL(library, initialize_ex_fn, "Py_InitializeEx");
    decode_locale_fn decode = SYMBOL(library, decode_locale_fn, "Py_DecodeLocale");
    set_wide_fn set_home = SYMBOL(library, set_wide_fn, "Py_SetPythonHome");
    set_wide_fn set_program = SYMBOL(library, set_wide_fn, "Py_SetProgramName");
    int *no_site = SYMBOL(library, int *, "Py_NoSiteFlag");
    int *ignore_environment = SYMBOL(library, int *, "Py_IgnoreEnvironmentFlag");
    if (!pre_init || !pre_initialize || !initialize_ex || !decode || !set_home || !no_site || !ignore_environment) {
        guard_format(why, size, "%s lacks the functions to start it (it is not CPython 3.11 to 3.13)", python->library);
        return 0;
    }
    py_pre_config pre;
    memset(&pre, 0, sizeof pre);
    pre_init(&pre);
    pre.configure_locale = 0; /* the host's locale stays as it is */
    pre.coerce_c_locale = pre.coerce_c_locale_warn = 0;
    pre.utf8_mode = 1; /* file names are UTF-8 whatever the locale */
    pre.use_environment = 0, pre.isolated = 1, pre.parse_argv = 0;
    py_status status = pre_initialize(&pre);
    if (status.type != 0) {
        guard_format(why, size, "did not start (%s)", status.err_msg ? status.err_msg : "pre-initialisation failed");
        return 0;
    }
    /* Py_SetPythonHome and Py_SetProgramName keep their arguments: decoded once (UTF-8 now), never freed. */
    wchar_t *home = decode(python->home, NULL);
    wchar_t *program = python->executable[0] ? decode(python->executable, NULL) : NULL;
    if (!home || (python->executable[0] && !program)) {
        guard_format(why, size, "cannot take its home %s (not decodable)", python->home);
        return 0;
    }
    *no_site = 1, *ignore_environment = 1;
    set_home(home);
    if (program && set_program) set_program(program);
    initialize_ex(0); /* 0: no signal handlers, SIGINT and SIGPIPE stay the host's */
    return 1;
}

/* Start `python`: loaded privately and checked, then made global, initialised, the GIL released. */
static int start_python(const python_install *python, char *why, size_t size) {
    void *library = dlopen(python->library, RTLD_NOW | RTLD_LOCAL);
    if (!library) {
        guard_format(why, size, "cannot be loaded: %s", dlerror());
        return 0;
    }
    is_initialized_fn is_initialized = SYMBOL(library, is_initialized_fn, "Py_IsInitialized");
    save_thread_fn save_thread = SYMBOL(library, save_thread_fn, "PyEval_SaveThread");
    if (!is_initialized || !save_thread) {
        guard_format(why, size, "%s is not a CPython library", python->library);
        dlclose(library);
        return 0;
    }
    int started = 1;
    void *global = NULL;
    flockfile(stderr); /* the one lock all copies of the loader share: one starts Python at a time */
    if (!python_in_process()) {
        if (!(global = dlopen(python->library, RTLD_NOW | RTLD_NOLOAD | RTLD_GLOBAL))) { /* the same copy, global */
            guard_format(why, size, "cannot be made global: %s", dlerror());
            started = 0;
        } else if (dlsym(library, "PyInitConfig_Create")) {
            started = start_by_init_config(library, python, why, size);
        } else {
            started = start_by_legacy_calls(library, python, why, size);
        }
        if (started && !is_initialized()) {
            guard_format(why, size, "did not start");
            started = 0;
        }
        if (started) save_thread(); /* release the GIL: every call takes it with PyGILState_Ensure */
    }
    funlockfile(stderr);
    if (!started) { /* nothing of a Python that did not start stays in the process's global scope */
        if (global) dlclose(global);
        dlclose(library);
    }
    return started;
}

/* Try one candidate: report in `tried`, start it if usable. */
static int try_candidate(const char *label, int described, const python_install *python, char *why, char *tried,
                         size_t tried_size) {
    if (described && usable(python, why, WHY_SIZE) && start_python(python, why, WHY_SIZE)) return 1;
    appendf(tried, tried_size, "%s%s %s", tried[0] ? "; " : "", label, why);
    return 0;
}

static int find_and_start_python(const char *resources, char *error, size_t error_size) {
    char tried[2048] = "", why[WHY_SIZE] = "", label[PATH_MAX + 64], interpreter[PATH_MAX];
    static python_install python; /* large: not on the host's stack */
    const char *override = getenv(PYTHON_OVERRIDE_VARIABLE);
    if (override && override[0]) {
        memset(&python, 0, sizeof python);
        guard_format(label, sizeof label, "%s=%s", PYTHON_OVERRIDE_VARIABLE, override);
        int described;
        if (strstr(base_name(override), "libpython")) described = describe_library(override, &python, why, sizeof why);
        else if (!which(override, interpreter, sizeof interpreter))
            described = (guard_format(why, sizeof why, "is not an executable file"), 0);
        else described = query_interpreter(interpreter, &python, why, sizeof why);
        if (try_candidate(label, described, &python, why, tried, sizeof tried)) return 1;
    } else {
        memset(&python, 0, sizeof python);
        int described = read_recorded(resources, &python, why, sizeof why);
        guard_format(label, sizeof label, "the build's Python%s%s", described ? " " : "",
                     described ? python.executable : "");
        if (try_candidate(label, described, &python, why, tried, sizeof tried)) return 1;

        memset(&python, 0, sizeof python);
        const char *path = getenv("PATH");
        if (which("python3", interpreter, sizeof interpreter)) {
            guard_format(label, sizeof label, "python3 on PATH (%s)", interpreter);
            described = query_interpreter(interpreter, &python, why, sizeof why);
        } else {
            guard_format(label, sizeof label, "python3 on PATH (%s)", path ? path : "PATH unset");
            described = (guard_format(why, sizeof why, "not found"), 0);
        }
        if (try_candidate(label, described, &python, why, tried, sizeof tried)) return 1;
    }
    guard_format(error, error_size,
                 "no usable Python to run this FMU (it needs CPython >= 3.%d with a shared libpython, standard library "
                 "only): %s. Set %s to such a python3 or to its libpython3.X.so",
                 PYTHON_MIN_MINOR, tried, PYTHON_OVERRIDE_VARIABLE);
    return 0;
}

/* ------------------------------------------------------------------------------- the C API */

static int resolve_api(char *error, size_t error_size) {
    const char *missing = NULL;
#define RESOLVE(field, name)                                                                                      \
    if (!missing && !(*(void **)&api.field = dlsym(RTLD_DEFAULT, name))) missing = name;
    RESOLVE(GILState_Ensure, "PyGILState_Ensure")
    RESOLVE(GILState_Release, "PyGILState_Release")
    RESOLVE(IncRef, "Py_IncRef")
    RESOLVE(DecRef, "Py_DecRef")
    RESOLVE(Object_GetAttrString, "PyObject_GetAttrString")
    RESOLVE(Object_Call, "PyObject_Call")
    RESOLVE(Object_Str, "PyObject_Str")
    RESOLVE(Unicode_AsUTF8AndSize, "PyUnicode_AsUTF8AndSize")
    RESOLVE(Unicode_FromString, "PyUnicode_FromString")
    RESOLVE(Bytes_FromStringAndSize, "PyBytes_FromStringAndSize")
    RESOLVE(Bytes_AsStringAndSize, "PyBytes_AsStringAndSize")
    RESOLVE(Long_AsLong, "PyLong_AsLong")
    RESOLVE(Tuple_Size, "PyTuple_Size")
    RESOLVE(Tuple_GetItem, "PyTuple_GetItem")
    RESOLVE(Dict_New, "PyDict_New")
    RESOLVE(Dict_SetItemString, "PyDict_SetItemString")
    RESOLVE(Dict_GetItemString, "PyDict_GetItemString")
    RESOLVE(Dict_Clear, "PyDict_Clear")
    RESOLVE(CompileString, "Py_CompileString")
    RESOLVE(Eval_EvalCode, "PyEval_EvalCode")
    RESOLVE(Err_Occurred, "PyErr_Occurred")
    RESOLVE(Err_Fetch, "PyErr_Fetch")
    RESOLVE(Err_Clear, "PyErr_Clear")
    RESOLVE(Err_SetInterrupt, "PyErr_SetInterrupt")
#undef RESOLVE
    /* '#' formats take a Py_ssize_t length: the _SizeT variant where it still exists (3.11, 3.12) */
    *(void **)&api.VaBuildValue = dlsym(RTLD_DEFAULT, "_Py_VaBuildValue_SizeT");
    if (!api.VaBuildValue) *(void **)&api.VaBuildValue = dlsym(RTLD_DEFAULT, "Py_VaBuildValue");
    if (!missing && !api.VaBuildValue) missing = "Py_VaBuildValue";
    if (missing) guard_format(error, error_size, "the process's Python lacks %s: it is not a CPython >= 3.%d", missing,
                              PYTHON_MIN_MINOR);
    return !missing;
}

/* ----------------------------------------------------------------------------------- entry */

const python_api *python_runtime_start(const char *resources, char *error, size_t error_size) {
    pthread_mutex_lock(&load_lock);
    if (!api_ready) {
        const char *override = getenv(PYTHON_OVERRIDE_VARIABLE);
        if (failure[0] && strcmp(failure_override, override ? override : "") == 0) {
            guard_format(error, error_size, "%s", failure); /* the same search would fail the same way */
        } else {
            failure[0] = '\0';
            int ready = python_in_process() || find_and_start_python(resources, error, error_size);
            if (ready) api_ready = resolve_api(error, error_size);
            if (!api_ready) {
                guard_format(failure, sizeof failure, "%s", error);
                guard_format(failure_override, sizeof failure_override, "%s", override ? override : "");
            }
        }
    }
    const python_api *ready = api_ready ? &api : NULL;
    pthread_mutex_unlock(&load_lock);
    return ready;
}
