/* Start a CPython from its shared library (see python_start.h). */
#ifndef _WIN32
#define _GNU_SOURCE
#include "glibc_compat.h"
#endif

#include "python_start.h"

#include "python_config.h"
#include "text.h"

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <wchar.h>

typedef void (*pre_config_init_fn)(py_pre_config *);
typedef py_status (*pre_initialize_fn)(const py_pre_config *);
typedef void (*config_init_fn)(void *);
typedef py_status (*config_set_bytes_fn)(void *, wchar_t **, const char *);
typedef py_status (*list_append_fn)(py_wide_list *, const wchar_t *);
typedef wchar_t *(*decode_locale_fn)(const char *, size_t *);
typedef void (*raw_free_fn)(void *);
typedef py_status (*initialize_from_config_fn)(const void *);
typedef int (*is_initialized_fn)(void);
typedef void *(*save_thread_fn)(void);
typedef void *(*init_config_create_fn)(void);
typedef int (*init_config_set_int_fn)(void *, const char *, long long);
typedef int (*init_config_set_str_fn)(void *, const char *, const char *);
typedef int (*init_config_set_list_fn)(void *, const char *, size_t, char *const *);
typedef int (*initialize_from_init_config_fn)(void *);
typedef int (*init_config_error_fn)(void *, const char **);
typedef void (*init_config_free_fn)(void *);

#define SYMBOL(library, type, name) ((type)platform_symbol(library, name))

static int failed_status(py_status status, const char *what, char *why, size_t size) {
    if (status.type == 0) return 0;
    if (status.type == 2) text_format(why, size, "did not start (%s: exit %d)", what, status.exitcode);
    else text_format(why, size, "did not start (%s%s%s)", status.func ? status.func : what, status.func ? ": " : "",
             status.err_msg ? status.err_msg : "no reason given");
    return 1;
}

/* CPython 3.11 to 3.13: PyPreConfig, then PyConfig at the layout of its version. */
static int start_by_config(void *library, const python_install *python, char *why, size_t size) {
    const config_layout *layout = NULL;
    for (size_t k = 0; k < sizeof LAYOUTS / sizeof *LAYOUTS; k++)
        if (LAYOUTS[k].minor == python->minor) layout = &LAYOUTS[k];
    pre_config_init_fn pre_init = SYMBOL(library, pre_config_init_fn, "PyPreConfig_InitIsolatedConfig");
    pre_initialize_fn pre_initialize = SYMBOL(library, pre_initialize_fn, "Py_PreInitialize");
    config_init_fn init = SYMBOL(library, config_init_fn, "PyConfig_InitIsolatedConfig");
    config_set_bytes_fn set_bytes = SYMBOL(library, config_set_bytes_fn, "PyConfig_SetBytesString");
    list_append_fn append = SYMBOL(library, list_append_fn, "PyWideStringList_Append");
    decode_locale_fn decode = SYMBOL(library, decode_locale_fn, "Py_DecodeLocale");
    raw_free_fn raw_free = SYMBOL(library, raw_free_fn, "PyMem_RawFree");
    initialize_from_config_fn initialize = SYMBOL(library, initialize_from_config_fn, "Py_InitializeFromConfig");
    config_init_fn clear = SYMBOL(library, config_init_fn, "PyConfig_Clear");
    if (!layout || !pre_init || !pre_initialize || !init || !set_bytes || !append || !decode || !raw_free ||
        !initialize || !clear) {
        text_format(why, size, "%s is not a CPython 3.%d the FMU knows how to start (3.11 to 3.13, or 3.14 and newer)",
            python->library, python->minor);
        return 0;
    }
    py_pre_config pre;
    memset(&pre, 0, sizeof pre);
    pre_init(&pre);
    pre.configure_locale = 0; /* the host's locale stays as it is */
    pre.coerce_c_locale = pre.coerce_c_locale_warn = 0;
    pre.utf8_mode = 1; /* file names are UTF-8 whatever the locale */
    pre.use_environment = 0, pre.isolated = 1, pre.parse_argv = 0;
    if (failed_status(pre_initialize(&pre), "Py_PreInitialize", why, size)) return 0;

    char *config = calloc(1, layout->size + CONFIG_SPARE);
    if (!config) {
        text_format(why, size, "did not start (out of memory)");
        return 0;
    }
    init(config);
#define INT_FIELD(name) (*(int *)(config + layout->name))
    INT_FIELD(install_signal_handlers) = 0; /* SIGINT, SIGPIPE and the rest stay the host's */
    INT_FIELD(site_import) = 0;             /* no site-packages: the FMU needs the standard library only */
    INT_FIELD(write_bytecode) = 0;          /* nothing written beside the Python or the FMU */
    INT_FIELD(user_site_directory) = 0;
    INT_FIELD(use_environment) = 0; /* no PYTHONHOME, PYTHONPATH ... of the host */
    INT_FIELD(configure_c_stdio) = 0; /* the C streams' modes and buffering stay the host's */
    INT_FIELD(parse_argv) = 0;
    INT_FIELD(pathconfig_warnings) = 0;
#undef INT_FIELD
    int started = !failed_status(set_bytes(config, (wchar_t **)(void *)(config + layout->home), python->home),
                                 "its home", why, size);
    if (started && python->executable[0])
        started = !failed_status(set_bytes(config, (wchar_t **)(void *)(config + layout->program_name),
                                           python->executable), "its program name", why, size);
    for (int k = 0; started && k < 2 && python->search_path[k][0]; k++) {
        wchar_t *entry = decode(python->search_path[k], NULL);
        if (!entry) {
            text_format(why, size, "did not start (the path %s cannot be decoded)", python->search_path[k]);
            started = 0;
            break;
        }
        started = !failed_status(append((py_wide_list *)(void *)(config + layout->module_search_paths), entry),
                                 "its module search path", why, size);
        raw_free(entry);
        *(int *)(config + layout->module_search_paths_set) = 1;
    }
    if (started) started = !failed_status(initialize(config), "Py_InitializeFromConfig", why, size);
    clear(config);
    free(config);
    return started;
}

/* CPython 3.14 and newer (PEP 741): the whole configuration by name, nothing of its layout assumed. */
static int start_by_init_config(void *library, const python_install *python, char *why, size_t size) {
    init_config_create_fn create = SYMBOL(library, init_config_create_fn, "PyInitConfig_Create");
    init_config_set_int_fn set_int = SYMBOL(library, init_config_set_int_fn, "PyInitConfig_SetInt");
    init_config_set_str_fn set_str = SYMBOL(library, init_config_set_str_fn, "PyInitConfig_SetStr");
    init_config_set_list_fn set_list = SYMBOL(library, init_config_set_list_fn, "PyInitConfig_SetStrList");
    initialize_from_init_config_fn initialize =
        SYMBOL(library, initialize_from_init_config_fn, "Py_InitializeFromInitConfig");
    init_config_error_fn get_error = SYMBOL(library, init_config_error_fn, "PyInitConfig_GetError");
    init_config_free_fn release = SYMBOL(library, init_config_free_fn, "PyInitConfig_Free");
    void *config = create ? create() : NULL;
    if (!config || !set_int || !set_str || !set_list || !initialize || !get_error || !release) {
        text_format(why, size, "%s offers no way to start it without changing the host", python->library);
        if (config && release) release(config);
        return 0;
    }
    static const char *const zero[] = {"configure_locale", "install_signal_handlers", "site_import", "use_environment",
                                       "user_site_directory", "parse_argv", "write_bytecode", "configure_c_stdio"};
    int failed = set_int(config, "utf8_mode", 1) || set_int(config, "isolated", 1);
    for (size_t k = 0; !failed && k < sizeof zero / sizeof *zero; k++) failed = set_int(config, zero[k], 0);
    if (!failed) failed = set_str(config, "home", python->home);
    if (!failed && python->executable[0]) failed = set_str(config, "program_name", python->executable);
    char *paths[2];
    size_t n = 0;
    while (n < 2 && python->search_path[n][0]) paths[n] = (char *)python->search_path[n], n++;
    if (!failed && n) failed = set_list(config, "module_search_paths", n, paths);
    if (!failed) failed = initialize(config);
    const char *message = NULL;
    if (failed && get_error(config, &message) == 0) message = NULL;
    if (failed) text_format(why, size, "did not start (%s)", message ? message : "no reason given");
    release(config);
    return !failed;
}

/* ------------------------------------------------------------------------------- starting */

/* Load the libraries `python` names in its preload list (never given back: its extension modules use them). */
static int preload(const python_install *python, char *why, size_t size) {
    for (const char *name = python->preload; *name;) {
        size_t length = strcspn(name, ":");
        char path[PLATFORM_PATH_MAX];
        if (!text_fits(path, sizeof path, "%s" PLATFORM_SEPARATOR "%.*s", python->home, (int)length, name)) {
            text_format(why, size, "cannot load what it needs: a path is too long");
            return 0;
        }
        if (!platform_load(path, why, size)) return 0;
        name += length + (name[length] == ':');
    }
    return 1;
}

void *python_start(const python_install *python, char *why, size_t size) {
    if (!preload(python, why, size)) return NULL;
    void *library = platform_load(python->library, why, size);
    if (!library) return NULL;
    is_initialized_fn is_initialized = SYMBOL(library, is_initialized_fn, "Py_IsInitialized");
    save_thread_fn save_thread = SYMBOL(library, save_thread_fn, "PyEval_SaveThread");
    if (!is_initialized || !save_thread) {
        text_format(why, size, "%s is not a CPython library", python->library);
        platform_unload(library);
        return NULL;
    }
    void *global = platform_make_global(python->library, library, why, size);
    int started = global != NULL;
    if (started && platform_symbol(library, "PyInitConfig_Create"))
        started = start_by_init_config(library, python, why, size);
    else if (started)
        started = start_by_config(library, python, why, size);
    if (started && !is_initialized()) {
        text_format(why, size, "did not start");
        started = 0;
    }
    if (started) {
        save_thread(); /* release the GIL: every call takes it with PyGILState_Ensure */
        return library;
    }
    /* nothing of a Python that did not start stays in the process's global scope */
    if (global && global != library) platform_unload(global);
    platform_unload(library);
    return NULL;
}
