/* CPython's configuration structures as python_start.c fills them: PyStatus, PyWideStringList, PyPreConfig and
 * PyConfig, mirrored field for field for each minor version 3.11 to 3.13 (Include/cpython/initconfig.h), with
 * the fields Windows has of its own (MS_WINDOWS); the compiler lays them out for the target, as CPython's own
 * headers would.  tests/test_python_choice.py compiles the offsets of every field used here against the
 * Python.h of each CPython at hand.  CPython 3.14 and newer are configured by name (PEP 741): no mirror. */
#ifndef PYTHON_CONFIG_H
#define PYTHON_CONFIG_H

#include <stddef.h>
#include <stdint.h>
#include <wchar.h>

/* PyStatus, PyWideStringList and PyPreConfig, as CPython 3.11 to 3.13 lay them out
 * (Include/cpython/initconfig.h; the same in the three).  Windows has fields of its own (MS_WINDOWS). */
typedef struct {
    int type; /* 0 OK, 1 error, 2 exit */
    const char *func, *err_msg;
    int exitcode;
} py_status;

typedef struct {
    intptr_t length; /* Py_ssize_t */
    wchar_t **items;
} py_wide_list;

#ifdef _WIN32
#define WINDOWS_ONLY(field) field
#else
#define WINDOWS_ONLY(field)
#endif

typedef struct {
    int config_init, parse_argv, isolated, use_environment, configure_locale, coerce_c_locale, coerce_c_locale_warn;
    WINDOWS_ONLY(int legacy_windows_fs_encoding;)
    int utf8_mode, dev_mode, allocator;
} py_pre_config;

/* PyConfig, field for field, as each minor version lays it out: 3.11's fields, then what 3.12 and 3.13
 * add or drop (3.13's free-threaded build has one more, enable_gil: it is refused, python_runtime.c). */
#define PY_CONFIG(name, perf_profiling, int_max_str_digits, cpu_count, sys_path_0, isolated_interpreter)       \
    typedef struct {                                                                                          \
        int config_init, isolated, use_environment, dev_mode, install_signal_handlers, use_hash_seed;          \
        unsigned long hash_seed;                                                                              \
        int faulthandler, tracemalloc;                                                                        \
        perf_profiling                                                                                        \
        int import_time, code_debug_ranges, show_ref_count, dump_refs;                                        \
        wchar_t *dump_refs_file;                                                                              \
        int malloc_stats;                                                                                     \
        wchar_t *filesystem_encoding, *filesystem_errors, *pycache_prefix;                                    \
        int parse_argv;                                                                                       \
        py_wide_list orig_argv, argv, xoptions, warnoptions;                                                  \
        int site_import, bytes_warning, warn_default_encoding, inspect, interactive, optimization_level,       \
            parser_debug, write_bytecode, verbose, quiet, user_site_directory, configure_c_stdio,             \
            buffered_stdio;                                                                                   \
        wchar_t *stdio_encoding, *stdio_errors;                                                               \
        WINDOWS_ONLY(int legacy_windows_stdio;)                                                               \
        wchar_t *check_hash_pycs_mode;                                                                        \
        int use_frozen_modules, safe_path;                                                                    \
        int_max_str_digits                                                                                    \
        cpu_count                                                                                             \
        int pathconfig_warnings;                                                                              \
        wchar_t *program_name, *pythonpath_env, *home, *platlibdir;                                           \
        int module_search_paths_set;                                                                          \
        py_wide_list module_search_paths;                                                                     \
        wchar_t *stdlib_dir, *executable, *base_executable, *prefix, *base_prefix, *exec_prefix,              \
            *base_exec_prefix;                                                                                \
        int skip_source_first_line;                                                                           \
        wchar_t *run_command, *run_module, *run_filename;                                                     \
        sys_path_0                                                                                            \
        int install_importlib, init_main;                                                                     \
        isolated_interpreter                                                                                  \
        int is_python_build;                                                                                  \
    } name;

PY_CONFIG(py_config_311, , , , , int isolated_interpreter;)
PY_CONFIG(py_config_312, int perf_profiling;, int int_max_str_digits;, , , )
PY_CONFIG(py_config_313, int perf_profiling;, int int_max_str_digits;, int cpu_count;, wchar_t *sys_path_0;, )

/* Where the fields this file sets lie in each version's PyConfig. */
typedef struct {
    int minor;
    size_t size, install_signal_handlers, site_import, write_bytecode, user_site_directory, use_environment,
        configure_c_stdio, parse_argv, pathconfig_warnings, home, program_name, module_search_paths_set,
        module_search_paths;
} config_layout;

#define LAYOUT(minor, type)                                                                                   \
    {minor, sizeof(type), offsetof(type, install_signal_handlers), offsetof(type, site_import),               \
     offsetof(type, write_bytecode), offsetof(type, user_site_directory), offsetof(type, use_environment),     \
     offsetof(type, configure_c_stdio), offsetof(type, parse_argv), offsetof(type, pathconfig_warnings),       \
     offsetof(type, home), offsetof(type, program_name), offsetof(type, module_search_paths_set),              \
     offsetof(type, module_search_paths)}

static const config_layout LAYOUTS[] = {LAYOUT(11, py_config_311), LAYOUT(12, py_config_312),
                                        LAYOUT(13, py_config_313)};

/* Room behind the config for fields this file does not know (a debug build's run_presite). */
#define CONFIG_SPARE 256

#endif
