/* Choose, and if need be start, the CPython that runs the FMU's Python side (see python_runtime.h). */
#ifndef _WIN32
#define _GNU_SOURCE
#include "glibc_compat.h"
#endif

#include "python_runtime.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "identity.h"
#include "platform.h"
#include "text.h"

#define CONFIG_FILE "python.cfg" /* in resources/ of a lean FMU, written by the build */
#ifndef QUERY_TIMEOUT_MS /* the tests compile it smaller (-DQUERY_TIMEOUT_MS=2000), not to wait 20 s */
#define QUERY_TIMEOUT_MS 20000 /* a candidate interpreter must answer within this time */
#endif
#define WHY_SIZE 1024

static platform_mutex load_lock = PLATFORM_MUTEX_INIT;
static python_api api;
static int api_ready;
static int started_here;  /* this copy started the process's Python: it handles forks (python_runtime_fork_*) */
static int fork_gil = -1; /* the GIL state taken for a fork in progress */
static platform_mutex taking_gil = PLATFORM_MUTEX_INIT; /* held while a thread of a C host takes the GIL */
static char chosen[WHY_SIZE + PLATFORM_PATH_MAX]; /* which Python runs, and why */
static char failure[2048];                        /* why the last search failed ("" if none failed) */
static char failure_override[PLATFORM_PATH_MAX + 1]; /* DOUBLE_PENDULUM_FMU_PYTHON at that search */
static char carried_stdlib[PLATFORM_PATH_MAX];      /* the zipped standard library of the CPython this copy started */

/* ---------------------------------------------------------------------------------- helpers */

static void appendf(char *buffer, size_t size, const char *format, ...) __attribute__((format(printf, 3, 4)));
static void appendf(char *buffer, size_t size, const char *format, ...) {
    size_t used = strlen(buffer);
    if (used + 1 >= size) return;
    va_list args;
    va_start(args, format);
    char part[WHY_SIZE + PLATFORM_PATH_MAX];
    int n = vsnprintf(part, sizeof part, format, args);
    va_end(args);
    if (n > 0) text_format(buffer + used, size - used, "%s", part);
}

static const char *base_name(const char *path) {
    const char *base = path;
    for (const char *p = path; *p; p++)
        if (platform_is_separator(*p)) base = p + 1;
    return base;
}

/* The version "3.11.7" of the Python whose Py_GetVersion is `version` ("3.11.7 (main, ...)"), as numbers. */
static int parse_version(const char *version, int *major, int *minor) {
    return version && sscanf(version, "%d.%d", major, minor) == 2;
}

/* ------------------------------------------------------------------- a Python already here */

typedef enum { NONE_HERE, USABLE_HERE, REFUSED_HERE } in_process;

/* A CPython already in the process: used if it runs and is new enough, else refused with why. */
static in_process python_in_process(void **library, char *why, size_t size) {
    char path[PLATFORM_PATH_MAX] = "";
    if (!platform_loaded_python(library, path, sizeof path)) return NONE_HERE;
    int (*initialized)(void) = (int (*)(void))platform_symbol(*library, "Py_IsInitialized");
    const char *(*get_version)(void) = (const char *(*)(void))platform_symbol(*library, "Py_GetVersion");
    const char *version = get_version ? get_version() : NULL;
    int major = 0, minor = 0;
    const char *where = path[0] ? path : "the host's executable";
    if (!parse_version(version, &major, &minor)) {
        text_format(why, size, "the Python in this process (%s) does not say its version: it is not a CPython",
                     where);
        return REFUSED_HERE;
    }
    char short_version[32];
    text_format(short_version, sizeof short_version, "%.*s", (int)strcspn(version, " "), version);
    if (major != 3 || minor < PYTHON_MIN_MINOR) {
        text_format(why, size, "this process runs CPython %s (%s), older than the 3.%d the FMU's Python side "
                     "needs; the FMU uses the Python of its host and never loads a second one beside it: run it "
                     "from CPython >= 3.%d, or from a host without Python%s", short_version, where, PYTHON_MIN_MINOR,
                     PYTHON_MIN_MINOR, identity_python_library[0] ? " (it carries its own)" : "");
        return REFUSED_HERE;
    }
    if (!initialized || !initialized()) {
        text_format(why, size, "a CPython %s is loaded in this process (%s) but was not started by its owner; "
                     "the FMU does not start it, nor load a second Python beside it", short_version, where);
        return REFUSED_HERE;
    }
    text_format(chosen, sizeof chosen, "CPython %s already running in this process (%s): the FMU uses the Python "
                 "of its host, or the one an earlier FMU started", short_version, where);
    return USABLE_HERE;
}

/* ------------------------------------------------------------------------------ candidates */

/* Ask `interpreter` for its version, libpython, home and base executable (POSIX). */
static int query_interpreter(const char *interpreter, python_install *python, char *why, size_t size) {
    static const char query[] =
        "import os, sys, sysconfig as c\n"
        "v = sys.version_info\n"
        "print(sys.implementation.name, v[0], v[1])\n"
        "print(os.path.join(c.get_config_var('LIBDIR') or '', c.get_config_var('INSTSONAME') or ''))\n"
        "print(sys.base_prefix)\n"
        "print(getattr(sys, '_base_executable', '') or sys.executable)\n";
    char *argv[] = {(char *)interpreter, "-I", "-S", "-c", (char *)query, NULL};
    char output[4 * PLATFORM_PATH_MAX];
    if (!platform_run(argv, output, sizeof output, QUERY_TIMEOUT_MS, why, size)) return 0;
    char implementation[32] = "";
    char *line = strchr(output, '\n');
    if (!line || sscanf(output, "%31s %d %d", implementation, &python->major, &python->minor) != 3) {
        text_format(why, size, "did not answer as a Python does");
        return 0;
    }
    char *fields[3] = {python->library, python->home, python->executable};
    for (int k = 0; k < 3; k++) {
        char *begin = line + 1, *end = strchr(begin, '\n');
        if (!end) {
            text_format(why, size, "did not answer as a Python does");
            return 0;
        }
        *end = '\0';
        if (!text_fits(fields[k], PLATFORM_PATH_MAX, "%s", begin)) {
            text_format(why, size, "answered with a path longer than %d bytes", PLATFORM_PATH_MAX - 1);
            return 0;
        }
        line = end;
    }
    if (strcmp(implementation, "cpython") != 0) {
        text_format(why, size, "is %s, not CPython", implementation);
        return 0;
    }
    return 1;
}

/* The standard library's landmark under `home` ("encodings" is what CPython imports first). */
static int has_standard_library(const python_install *python) {
    char landmark[PLATFORM_PATH_MAX];
    return (text_fits(landmark, sizeof landmark, "%s/lib/python%d.%d/encodings/__init__.py", python->home, python->major,
                 python->minor) && platform_is_file(landmark)) ||
           (text_fits(landmark, sizeof landmark, "%s/Lib/encodings/__init__.py", python->home) &&
            platform_is_file(landmark)) ||
           (text_fits(landmark, sizeof landmark, "%s/python%d%d.zip", python->home, python->major, python->minor) &&
            platform_is_file(landmark));
}

/* A libpython named directly: its version from the file name (libpython3.X.so..., python3X.dll), its home
 * from where it lies (POSIX: <home>/lib/libpython3.X.so or <home>/lib/<multiarch>/libpython3.X.so; Windows:
 * the DLL's own folder). */
static int describe_library(const char *library, python_install *python, char *why, size_t size) {
    const char *name = base_name(library);
    if (sscanf(name, "libpython%d.%d", &python->major, &python->minor) != 2) {
        int digits = 0;
        if (sscanf(name, "python%d.dll", &digits) != 1 || digits < 30) {
            text_format(why, size, "is neither a python3 interpreter nor a libpython3.X.so or python3X.dll");
            return 0;
        }
        python->major = 3, python->minor = digits >= 300 ? digits - 300 : digits - 30; /* python311.dll: 3.11 */
    }
    if (!platform_is_file(library) || !text_fits(python->library, PLATFORM_PATH_MAX, "%s", library)) {
        text_format(why, size, "does not exist");
        return 0;
    }
    char home[PLATFORM_PATH_MAX];
    memcpy(home, python->library, sizeof home);
    for (int up = 0; up < 3; up++) {
        platform_parent_folder(home);
        memcpy(python->home, home, sizeof home);
        if (has_standard_library(python)) {
            if (!text_fits(python->executable, PLATFORM_PATH_MAX, "%s/bin/python%d.%d", home, python->major,
                      python->minor) ||
                !platform_is_file(python->executable))
                python->executable[0] = '\0';
            return 1;
        }
    }
    text_format(why, size, "has no standard library beside it (lib/python%d.%d/encodings, Lib/encodings or "
                 "python%d%d.zip)", python->major, python->minor, python->major, python->minor);
    return 0;
}

/* The interpreter recorded by the build in resources/python.cfg (key=value lines; a lean FMU's). */
static int read_recorded(const char *resources, python_install *python, char *why, size_t size) {
    char path[PLATFORM_PATH_MAX];
    if (!text_fits(path, sizeof path, "%s/%s", resources, CONFIG_FILE)) {
        text_format(why, size, "none recorded (the resources folder's path is too long)");
        return 0;
    }
    FILE *file = platform_open_text(path);
    if (!file) {
        text_format(why, size, "none recorded (%s missing)", path);
        return 0;
    }
    char line[PLATFORM_PATH_MAX + 32];
    int complete = 1;
    while (fgets(line, sizeof line, file)) {
        line[strcspn(line, "\r\n")] = '\0';
        char *value = strchr(line, '=');
        if (!value || line[0] == '#') continue;
        *value++ = '\0';
        if (strcmp(line, "library") == 0) complete &= text_fits(python->library, PLATFORM_PATH_MAX, "%s", value);
        else if (strcmp(line, "home") == 0) complete &= text_fits(python->home, PLATFORM_PATH_MAX, "%s", value);
        else if (strcmp(line, "executable") == 0) complete &= text_fits(python->executable, PLATFORM_PATH_MAX, "%s", value);
        else if (strcmp(line, "version") == 0) complete &= sscanf(value, "%d.%d", &python->major, &python->minor) == 2;
    }
    fclose(file);
    if (!complete) {
        text_format(why, size, "recorded in %s, which is malformed", path);
        return 0;
    }
    if (!platform_is_file(python->library) && python->executable[0] && !platform_is_file(python->executable)) {
        text_format(why, size, "not found (%s and %s are gone)", python->executable,
                     python->library[0] ? python->library : "its libpython");
        return 0;
    }
    return 1;
}

/* The CPython this FMU carries beside its binary (a self-contained FMU; identity.c names its files). */
static int describe_bundled(python_install *python, char *why, size_t size) {
    char folder[PLATFORM_PATH_MAX];
    if (!platform_own_folder(folder, sizeof folder)) {
        text_format(why, size, "cannot be found (the folder of the FMU's binary is unknown)");
        return 0;
    }
    python->major = 3, python->minor = identity_python_minor;
    int complete = text_fits(python->library, PLATFORM_PATH_MAX, "%s" PLATFORM_SEPARATOR "%s", folder,
                             identity_python_library) &&
                   text_fits(python->home, PLATFORM_PATH_MAX, "%s", folder) &&
                   text_fits(python->search_path[0], PLATFORM_PATH_MAX, "%s" PLATFORM_SEPARATOR "%s", folder,
                             identity_python_stdlib) &&
                   text_fits(python->search_path[1], PLATFORM_PATH_MAX, "%s", folder) &&
                   text_fits(python->preload, PLATFORM_PATH_MAX, "%s", identity_python_preload);
    if (!complete) text_format(why, size, "cannot be found (the path of the FMU's binaries folder is too long)");
    else if (!platform_is_file(python->library))
        text_format(why, size, "is damaged: %s is missing (extract the whole FMU again)", python->library);
    else if (!platform_is_file(python->search_path[0]))
        text_format(why, size, "is damaged: %s is missing (extract the whole FMU again)", python->search_path[0]);
    else
        return 1;
    return 0;
}

/* Can `python` run the FMU: CPython >= 3.11 with a shared libpython and its standard library? */
static int usable(const python_install *python, char *why, size_t size) {
    if (python->major != 3 || python->minor < PYTHON_MIN_MINOR)
        text_format(why, size, "is Python %d.%d, older than 3.%d", python->major, python->minor, PYTHON_MIN_MINOR);
    else if (!python->library[0] || !platform_is_file(python->library))
        text_format(why, size, "is Python %d.%d without a shared libpython (%s missing)", python->major,
                     python->minor, python->library[0] ? python->library : "libpython3.X.so");
    else if (!python->search_path[0][0] && !has_standard_library(python))
        text_format(why, size, "has no standard library at %s", python->home);
    else
        return 1;
    return 0;
}

/* Try one candidate: start it if usable (*library: its handle), else report it in `tried`. */
static int try_candidate(const char *label, int described, const python_install *python, char *why, char *tried,
                         size_t tried_size, void **library) {
    int ready = 0;
    if (described && usable(python, why, WHY_SIZE)) {
        platform_lock_process(); /* one copy of the loader starts Python at a time; another may have by now */
        char refused[WHY_SIZE] = "";
        in_process here = python_in_process(library, refused, sizeof refused);
        if (here == NONE_HERE) ready = started_here = (*library = python_start(python, why, WHY_SIZE)) != NULL;
        if (started_here) platform_pin_self(); /* its fork handlers must stay (python_runtime_fork_prepare) */
        platform_unlock_process();
        if (here == USABLE_HERE) return 1;
        if (here == REFUSED_HERE) text_format(why, WHY_SIZE, "%s", refused);
        if (ready) {
            const char *(*get_version)(void) = (const char *(*)(void))platform_symbol(*library, "Py_GetVersion");
            const char *version = get_version ? get_version() : "";
            text_format(chosen, sizeof chosen, "%s: CPython %.*s (%s)", label, (int)strcspn(version, " "), version,
                         python->library);
        }
    }
    if (!ready) appendf(tried, tried_size, "%s%s %s", tried[0] ? "; " : "", label, why);
    return ready;
}

/* Find a CPython and start it (*library: its handle); 0 and why in `error` if none can run the FMU. */
static int find_and_start_python(const char *resources, char *error, size_t error_size, void **library) {
    char tried[2048] = "", why[WHY_SIZE] = "", label[PLATFORM_PATH_MAX + 64], interpreter[PLATFORM_PATH_MAX];
    char override_buffer[PLATFORM_PATH_MAX];
    static python_install python; /* large: not on the host's stack */
    int ready = 0;
    const char *override = platform_getenv(PYTHON_OVERRIDE_VARIABLE, override_buffer, sizeof override_buffer);
    if (override && override[0]) {
        memset(&python, 0, sizeof python);
        text_format(label, sizeof label, "%s=%s", PYTHON_OVERRIDE_VARIABLE, override);
        int described;
        const char *name = base_name(override);
        if (strstr(name, "libpython") || (strncmp(name, "python", 6) == 0 && strstr(name, ".dll")))
            described = describe_library(override, &python, why, sizeof why);
        else if (!platform_which(override, interpreter, sizeof interpreter))
            described = (text_format(why, sizeof why, "is not an executable file"), 0);
        else described = query_interpreter(interpreter, &python, why, sizeof why);
        ready = try_candidate(label, described, &python, why, tried, sizeof tried, library);
    } else if (identity_python_library[0]) {
        memset(&python, 0, sizeof python);
        int described = describe_bundled(&python, why, sizeof why);
        ready = try_candidate("the CPython this FMU carries", described, &python, why, tried, sizeof tried, library);
        if (ready && strstr(chosen, "the CPython this FMU carries") == chosen)  /* started here, not another FMU's */
            text_format(carried_stdlib, sizeof carried_stdlib, "%s", python.search_path[0]);
    } else {
        memset(&python, 0, sizeof python);
        int described = read_recorded(resources, &python, why, sizeof why);
        text_format(label, sizeof label, "the build's Python%s%s", described ? " " : "",
                     described ? python.executable : "");
        ready = try_candidate(label, described, &python, why, tried, sizeof tried, library);
        if (!ready) {
            memset(&python, 0, sizeof python);
            char path_buffer[PLATFORM_PATH_MAX];
            const char *path = platform_getenv("PATH", path_buffer, sizeof path_buffer);
            if (platform_which("python3", interpreter, sizeof interpreter)) {
                text_format(label, sizeof label, "python3 on PATH (%s)", interpreter);
                described = query_interpreter(interpreter, &python, why, sizeof why);
            } else {
                text_format(label, sizeof label, "python3 on PATH (%s)", path ? path : "PATH unset");
                described = (text_format(why, sizeof why, "not found"), 0);
            }
            ready = try_candidate(label, described, &python, why, tried, sizeof tried, library);
        }
    }
    if (!ready)
        text_format(error, error_size,
                     "no usable Python to run this FMU (it needs CPython >= 3.%d with a shared libpython, standard "
                     "library only): %s. Set %s to such a python3 or to its libpython3.X.so%s", PYTHON_MIN_MINOR,
                     tried, PYTHON_OVERRIDE_VARIABLE, identity_python_library[0] ? " (or python3X.dll), or extract "
                     "the whole FMU again" : "");
    return ready;
}

/* ------------------------------------------------------------------------------- the C API */

static int resolve_api(void *library, char *error, size_t error_size) {
    const char *missing = NULL;
#define RESOLVE(field, name)                                                                                      \
    if (!missing && !(*(void **)&api.field = platform_symbol(library, name))) missing = name;
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
    RESOLVE(Err_NormalizeException, "PyErr_NormalizeException")
    RESOLVE(Exception_SetTraceback, "PyException_SetTraceback")
    RESOLVE(GILState_GetThisThreadState, "PyGILState_GetThisThreadState")
    RESOLVE(Thread_get_thread_ident, "PyThread_get_thread_ident")
    RESOLVE(ThreadState_SetAsyncExc, "PyThreadState_SetAsyncExc")
    RESOLVE(None, "_Py_NoneStruct")
#undef RESOLVE
    /* POSIX only (a Windows CPython has no fork): python_runtime_fork_prepare needs all three */
    *(void **)&api.OS_BeforeFork = platform_symbol(library, "PyOS_BeforeFork");
    *(void **)&api.OS_AfterFork_Parent = platform_symbol(library, "PyOS_AfterFork_Parent");
    *(void **)&api.OS_AfterFork_Child = platform_symbol(library, "PyOS_AfterFork_Child");
    /* '#' formats take a Py_ssize_t length: the _SizeT variant where it still exists (3.11, 3.12) */
    *(void **)&api.VaBuildValue = platform_symbol(library, "_Py_VaBuildValue_SizeT");
    if (!api.VaBuildValue) *(void **)&api.VaBuildValue = platform_symbol(library, "Py_VaBuildValue");
    if (!missing && !api.VaBuildValue) missing = "Py_VaBuildValue";
    if (missing) text_format(error, error_size, "the process's Python lacks %s: it is not a CPython >= 3.%d", missing,
                              PYTHON_MIN_MINOR);
    return !missing;
}

/* ----------------------------------------------------------------------------------- entry */

const python_api *python_runtime_start(const char *resources, char *error, size_t error_size, const char **said) {
    platform_lock(&load_lock);
    if (!api_ready) {
        char buffer[PLATFORM_PATH_MAX];
        const char *override = platform_getenv(PYTHON_OVERRIDE_VARIABLE, buffer, sizeof buffer);
        if (failure[0] && strcmp(failure_override, override ? override : "") == 0) {
            text_format(error, error_size, "%s", failure); /* the same search would fail the same way */
        } else {
            failure[0] = '\0';
            void *library = NULL;
            in_process here = python_in_process(&library, error, error_size);
            int ready = here == USABLE_HERE ||
                        (here == NONE_HERE && find_and_start_python(resources, error, error_size, &library));
            if (ready) api_ready = resolve_api(library, error, error_size);
            if (!api_ready) {
                text_format(failure, sizeof failure, "%s", error);
                text_format(failure_override, sizeof failure_override, "%s", override ? override : "");
            }
        }
    }
    const python_api *ready = api_ready ? &api : NULL;
    if (said) *said = ready ? chosen : NULL;
    platform_unlock(&load_lock);
    return ready;
}

int python_runtime_take_gil(void) {
    if (!started_here) return api.GILState_Ensure();
    platform_lock(&taking_gil);
    int gil = api.GILState_Ensure();
    platform_unlock(&taking_gil);
    return gil;
}

/* The fork handlers run in the forking thread alone (prepare, then parent or child): no lock of their own. */
void python_runtime_fork_prepare(void) {
    if (started_here && api_ready && api.OS_BeforeFork && api.OS_AfterFork_Parent && api.OS_AfterFork_Child) {
        /* the GIL first, as every call takes it before any lock of this copy */
        platform_lock(&taking_gil); /* no thread between its PyThreadState and the GIL */
        fork_gil = api.GILState_Ensure();
        api.OS_BeforeFork();
    }
    platform_lock(&load_lock);
}

/* After the fork, in either process: let go of what prepare took, with Python's own after-fork step between. */
static void after_fork(void (*python_after_fork)(void)) {
    platform_unlock(&load_lock);
    if (fork_gil < 0) return;
    python_after_fork();
    int gil = fork_gil;
    fork_gil = -1;
    api.GILState_Release(gil);
    platform_unlock(&taking_gil);
}

void python_runtime_fork_parent(void) { after_fork(api.OS_AfterFork_Parent); }

/* In the child Python forgets the threads it does not have; its only thread holds the GIL until after_fork. */
void python_runtime_fork_child(void) { after_fork(api.OS_AfterFork_Child); }

const char *python_runtime_stdlib(void) {
    platform_lock(&load_lock);
    const char *path = carried_stdlib; /* written once, under the lock, before the API was ready */
    platform_unlock(&load_lock);
    return path;
}
