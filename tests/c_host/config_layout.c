/* The loader's mirrors of CPython's configuration structures (fmu_src/loader/python_config.h) against CPython's
 * own Python.h: compiles (and exits 0) only where every field the loader sets lies where CPython has it, and the
 * structures have CPython's sizes.  tests/test_python_choice.py compiles it against each CPython 3.11 to 3.13 at
 * hand (-I its include folder and the loader's). */
#include <Python.h>
#include <stddef.h>

#include "python_config.h"

#if PY_MINOR_VERSION == 11
typedef py_config_311 mirror;
#elif PY_MINOR_VERSION == 12
typedef py_config_312 mirror;
#elif PY_MINOR_VERSION == 13
typedef py_config_313 mirror;
#else
#error "the loader mirrors PyConfig for CPython 3.11 to 3.13 only (3.14 and newer: PEP 741, by name)"
#endif

#define SAME(field) _Static_assert(offsetof(PyConfig, field) == offsetof(mirror, field), "PyConfig." #field);
SAME(install_signal_handlers) SAME(site_import) SAME(write_bytecode) SAME(user_site_directory)
SAME(use_environment) SAME(configure_c_stdio) SAME(parse_argv) SAME(pathconfig_warnings) SAME(home)
SAME(program_name) SAME(module_search_paths_set) SAME(module_search_paths)
_Static_assert(sizeof(PyConfig) == sizeof(mirror), "sizeof PyConfig");

#define PRE(field) _Static_assert(offsetof(PyPreConfig, field) == offsetof(py_pre_config, field), "PyPreConfig." #field);
PRE(parse_argv) PRE(isolated) PRE(use_environment) PRE(configure_locale) PRE(coerce_c_locale)
PRE(coerce_c_locale_warn) PRE(utf8_mode)
_Static_assert(sizeof(PyPreConfig) == sizeof(py_pre_config), "sizeof PyPreConfig");

_Static_assert(sizeof(PyStatus) == sizeof(py_status), "sizeof PyStatus");
_Static_assert(offsetof(PyStatus, err_msg) == offsetof(py_status, err_msg), "PyStatus.err_msg");
_Static_assert(offsetof(PyStatus, exitcode) == offsetof(py_status, exitcode), "PyStatus.exitcode");
_Static_assert(offsetof(PyWideStringList, items) == offsetof(py_wide_list, items), "PyWideStringList.items");

int main(void) { return 0; }
