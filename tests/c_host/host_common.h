/* What the tests' C hosts (fmi2_host.c, fmi3_host.c) share: a record of the host's environment and
 * signal handlers, to show that the FMU left them as it found them; loading the FMU's library and its
 * symbols; the check of an FMI call's status (fmi2Warning and fmi3Warning are both 1).
 *
 * The hosts build for Linux (gcc, clang) and for Windows (x86_64-windows-gnu with zig cc, run under Wine
 * by tests/wine.py). Everything that differs between the two is in the section "the platform" below, so
 * that the hosts themselves have no _WIN32 in them: the command line (Windows: read as UTF-16 and handed
 * to main as UTF-8), the FMU's library and resource location under its folder, loading a library and a
 * symbol, opening a file by a UTF-8 name, CPU time, the process's memory and the snapshot of the
 * environment (and, on Linux only, of the signal handlers). Every path is UTF-8 in the hosts. */
#ifndef HOST_COMMON_H
#define HOST_COMMON_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The functions here are static inline: a host that uses only some of them (fmi2_torture.c) compiles
 * without unused-function warnings. */

/* ---------------------------------------------------------------------------------------- the platform */
#ifdef _WIN32
#define WIN32_LEAN_AND_MEAN
#include <windows.h>
#include <fcntl.h>
#include <io.h>
#include <psapi.h>
#include <shellapi.h>
#include <wchar.h>

typedef HMODULE host_library;

/* `wide` as UTF-8 in memory of its own (free it), NULL if it is not valid UTF-16. */
static inline char *utf8_from_wide(const wchar_t *wide) {
    int size = WideCharToMultiByte(CP_UTF8, WC_ERR_INVALID_CHARS, wide, -1, NULL, 0, NULL, NULL);
    char *text = size > 0 ? malloc((size_t)size) : NULL;
    if (text && WideCharToMultiByte(CP_UTF8, WC_ERR_INVALID_CHARS, wide, -1, text, size, NULL, NULL) != size)
        free(text), text = NULL;
    return text;
}

/* `text` (UTF-8) as UTF-16 in memory of its own (free it), NULL if it is not valid UTF-8. */
static inline wchar_t *wide_from_utf8(const char *text) {
    int size = MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, text, -1, NULL, 0);
    wchar_t *wide = size > 0 ? malloc(sizeof(wchar_t) * (size_t)size) : NULL;
    if (wide && MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, text, -1, wide, size) != size)
        free(wide), wide = NULL;
    return wide;
}

/* `path` (a Windows path, UTF-8) as a file URI into `uri` (FMI 2's fmuResourceLocation): "file:///C:/a/b"
 * for a drive path, "file://server/share/a" for a UNC path; every byte but the unreserved characters of RFC
 * 3986, '/' and the drive's ':' percent-encoded, as Python's pathlib writes a URI (fmpy's). 0 if it does
 * not fit. */
static inline int file_uri(const char *path, char *uri, size_t size) {
    static const char hex[] = "0123456789ABCDEF";
    int unc = path[0] == '\\' && path[1] == '\\';
    int written = snprintf(uri, size, "%s", unc ? "file:" : "file:///");
    if (written < 0 || (size_t)written >= size) return 0;
    size_t n = (size_t)written;
    for (const unsigned char *p = (const unsigned char *)path; *p; p++) {
        unsigned char c = *p == '\\' ? '/' : *p;
        int plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    strchr("-._~/", c) || (!unc && c == ':' && p == (const unsigned char *)path + 1);
        if (n + (plain ? 1 : 3) >= size) return 0;
        if (plain) uri[n++] = (char)c;
        else uri[n++] = '%', uri[n++] = hex[c >> 4], uri[n++] = hex[c & 15];
    }
    uri[n] = '\0';
    return 1;
}
#else
#include <dlfcn.h>
#include <signal.h>
#include <time.h>

typedef void *host_library;
extern char **environ;
static const int SIGNALS[] = {SIGINT, SIGTERM, SIGPIPE, SIGCHLD, SIGXFSZ, SIGSEGV};
#define N_SIGNALS (sizeof SIGNALS / sizeof SIGNALS[0])
#endif

#ifdef _WIN32
/* The host's last word on an exception nothing handled (a crash in the FMU): one line on stderr and exit
 * status 9, where Windows would end it with the exception's code, whose low byte (what Wine hands on as
 * the exit status, 5 for an access violation) reads as one of the host's statuses, and Wine's debugger
 * would write its dump into stdout. */
static inline LONG WINAPI crashed(EXCEPTION_POINTERS *exception) {
    fflush(stdout);
    fprintf(stderr, "crashed: unhandled exception 0x%08lX at %p\n",
            (unsigned long)exception->ExceptionRecord->ExceptionCode, exception->ExceptionRecord->ExceptionAddress);
    fflush(stderr);
    TerminateProcess(GetCurrentProcess(), 9);
    return EXCEPTION_EXECUTE_HANDLER;
}
#endif

/* Call first in main: on Windows `*argv` becomes the command line as UTF-8 (read as UTF-16, so that a
 * non-ASCII path arrives whatever the code page; kept for the process's life), stdout and stderr write
 * "\n" as it is (binary mode: the output is byte for byte Linux's), and a crash or a missing file ends the
 * host (exit status 9 for a crash: `crashed`) instead of opening a dialog box. Nothing on Linux, where a
 * crash ends the host by its signal. */
static inline void host_start(int *argc, char ***argv) {
#ifdef _WIN32
    SetUnhandledExceptionFilter(crashed);
    int n = 0;
    wchar_t **wide = CommandLineToArgvW(GetCommandLineW(), &n);
    char **utf8 = wide ? calloc((size_t)n + 1, sizeof *utf8) : NULL;
    for (int k = 0; utf8 && k < n; k++)
        if (!(utf8[k] = utf8_from_wide(wide[k]))) utf8 = NULL;
    if (!utf8) {
        fprintf(stderr, "cannot read the command line as UTF-8\n");
        exit(2);
    }
    LocalFree(wide);
    *argc = n;
    *argv = utf8;
    _setmode(_fileno(stdout), _O_BINARY);
    _setmode(_fileno(stderr), _O_BINARY);
    SetErrorMode(SEM_FAILCRITICALERRORS | SEM_NOGPFAULTERRORBOX | SEM_NOOPENFILEERRORBOX);
#else
    (void)argc;
    (void)argv;
#endif
}

/* The FMU's library and its resource location, for FMI `fmi_version` (2 or 3), under the extracted FMU
 * `dir`: FMI 2 binaries/linux64/ID.so or binaries/win64/ID.dll and the file URI of resources/; FMI 3
 * binaries/x86_64-linux/ID.so or binaries/x86_64-windows/ID.dll and the path of resources/ with a
 * trailing separator. On Linux `dir` is taken as given (as the hosts always have, the URI not encoded); on
 * Windows it is made absolute first (LoadLibraryEx's altered search path wants an absolute path) and the
 * URI is percent-encoded. 0 (after saying why) if a path does not fit its buffer. */
static inline int fmu_locations(const char *dir, const char *identifier, int fmi_version, char *library,
                                size_t library_size, char *resources, size_t resources_size) {
    int a, b;
#ifdef _WIN32
    wchar_t *wide = wide_from_utf8(dir);
    DWORD length = wide ? GetFullPathNameW(wide, 0, NULL, NULL) : 0;
    wchar_t *full = length ? malloc(sizeof(wchar_t) * length) : NULL;
    char *absolute = full && GetFullPathNameW(wide, length, full, NULL) < length ? utf8_from_wide(full) : NULL;
    free(wide);
    free(full);
    if (!absolute) {
        fprintf(stderr, "cannot make %s an absolute path\n", dir);
        return 0;
    }
    size_t end = strlen(absolute);
    while (end > 3 && (absolute[end - 1] == '\\' || absolute[end - 1] == '/')) absolute[--end] = '\0';
    a = snprintf(library, library_size, "%s\\binaries\\%s\\%s.dll", absolute,
                 fmi_version == 2 ? "win64" : "x86_64-windows", identifier);
    if (fmi_version == 2) {
        char folder[32768]; /* the longest Windows path */
        b = snprintf(folder, sizeof folder, "%s\\resources", absolute);
        if (b >= 0 && (size_t)b < sizeof folder && !file_uri(folder, resources, resources_size)) b = -1;
    } else {
        b = snprintf(resources, resources_size, "%s\\resources\\", absolute);
    }
    free(absolute);
#else
    a = snprintf(library, library_size, "%s/binaries/%s/%s.so", dir, fmi_version == 2 ? "linux64" : "x86_64-linux",
                 identifier);
    b = fmi_version == 2 ? snprintf(resources, resources_size, "file://%s/resources", dir)
                         : snprintf(resources, resources_size, "%s/resources/", dir);
#endif
    if (a < 0 || (size_t)a >= library_size || b < 0 || (size_t)b >= resources_size) {
        fprintf(stderr, "the FMU's path is too long: %s\n", dir);
        return 0;
    }
    return 1;
}

/* Load the library at `path` (UTF-8); NULL, after saying why on stderr, if it cannot be loaded. Windows:
 * LoadLibraryExW with LOAD_WITH_ALTERED_SEARCH_PATH, so that a DLL the library needs is found beside it. */
static inline host_library load_library(const char *path) {
#ifdef _WIN32
    wchar_t *wide = wide_from_utf8(path);
    HMODULE library = wide ? LoadLibraryExW(wide, NULL, LOAD_WITH_ALTERED_SEARCH_PATH) : NULL;
    DWORD error = GetLastError();
    free(wide);
    if (!library) {
        char reason[512] = "";
        FormatMessageA(FORMAT_MESSAGE_FROM_SYSTEM | FORMAT_MESSAGE_IGNORE_INSERTS, NULL, error, 0, reason,
                       sizeof reason, NULL);
        reason[strcspn(reason, "\r\n")] = '\0';
        fprintf(stderr, "cannot load %s: error %lu %s\n", path, (unsigned long)error, reason);
    }
    return library;
#else
    void *library = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!library) fprintf(stderr, "cannot load %s: %s\n", path, dlerror());
    return library;
#endif
}

static inline void close_library(host_library library) {
#ifdef _WIN32
    FreeLibrary(library);
#else
    dlclose(library);
#endif
}

/* A function of the FMU's library; a missing one ends the host with exit status 3. */
static inline void *symbol(host_library library, const char *name) {
#ifdef _WIN32
    void *f = (void *)GetProcAddress(library, name);
#else
    void *f = dlsym(library, name);
#endif
    if (!f) {
        fprintf(stderr, "missing %s\n", name);
        exit(3);
    }
    return f;
}

/* fopen for a UTF-8 `path` (Windows: _wfopen, fopen would read it in the ANSI code page). */
static inline FILE *open_file(const char *path, const char *mode) {
#ifdef _WIN32
    wchar_t *wide_path = wide_from_utf8(path), *wide_mode = wide_from_utf8(mode);
    FILE *file = wide_path && wide_mode ? _wfopen(wide_path, wide_mode) : NULL;
    free(wide_path);
    free(wide_mode);
    return file;
#else
    return fopen(path, mode);
#endif
}

/* The process's CPU time (user and system) in seconds. */
static inline double cpu_seconds(void) {
#ifdef _WIN32
    FILETIME created, exited, kernel, user;
    if (!GetProcessTimes(GetCurrentProcess(), &created, &exited, &kernel, &user)) return 0.0;
    ULARGE_INTEGER k = {.u = {kernel.dwLowDateTime, kernel.dwHighDateTime}};
    ULARGE_INTEGER u = {.u = {user.dwLowDateTime, user.dwHighDateTime}};
    return 1e-7 * (double)(k.QuadPart + u.QuadPart); /* FILETIME counts 100 ns */
#else
    struct timespec now;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
#endif
}

/* The process's private memory in KiB, -1 if unknown: Windows the commit charge (PrivateUsage of
 * GetProcessMemoryInfo), Linux its nearest kin, the data segment (VmData of /proc/self/status: private
 * writable memory, heap and anonymous mappings, whether touched or not). A leak grows both. */
static inline long memory_kib(void) {
#ifdef _WIN32
    /* Windows 8 and later give the commit charge as PrivateUsage and as PagefileUsage, Windows 7 only as
     * PrivateUsage, Wine (8.0) only as PagefileUsage (Linux's RssAnon + VmSwap): the one that is there */
    PROCESS_MEMORY_COUNTERS_EX counters;
    memset(&counters, 0, sizeof counters);
    if (!K32GetProcessMemoryInfo(GetCurrentProcess(), (PROCESS_MEMORY_COUNTERS *)&counters, sizeof counters))
        return -1;
    return (long)((counters.PrivateUsage ? counters.PrivateUsage : counters.PagefileUsage) / 1024);
#else
    FILE *status = fopen("/proc/self/status", "r");
    char line[256];
    long kib = -1;
    while (status && fgets(line, sizeof line, status))
        if (strncmp(line, "VmData:", 7) == 0) kib = strtol(line + 7, NULL, 10);
    if (status) fclose(status);
    return kib;
#endif
}

/* How many CPython libraries the process has loaded (a host without Python: 0 before an FMU of this project
 * starts one, 1 after; never 2): Linux the distinct libpython3* files in /proc/self/maps, Windows the modules
 * named python3XY.dll (python3.dll, the stable ABI's forwarder, is no interpreter); -1 if unknown. */
static inline int pythons_loaded(void) {
#ifdef _WIN32
    HMODULE modules[1024];
    DWORD needed = 0;
    if (!K32EnumProcessModules(GetCurrentProcess(), modules, sizeof modules, &needed)) return -1;
    int count = 0;
    for (size_t k = 0; k < needed / sizeof *modules && k < sizeof modules / sizeof *modules; k++) {
        wchar_t name[MAX_PATH];
        if (!K32GetModuleBaseNameW(GetCurrentProcess(), modules[k], name, MAX_PATH)) continue;
        size_t digits = 0;
        while (name[7 + digits] >= L'0' && name[7 + digits] <= L'9' && _wcsnicmp(name, L"python3", 7) == 0) digits++;
        if (digits >= 1 && _wcsicmp(name + 7 + digits, L".dll") == 0) count++;
    }
    return count;
#else
    FILE *maps = fopen("/proc/self/maps", "r");
    char line[4352], seen[8][4096];
    int count = 0;
    while (maps && fgets(line, sizeof line, maps)) {
        char *path = strchr(line, '/');
        if (!path || !strstr(path, "/libpython3")) continue;
        path[strcspn(path, "\n")] = '\0';
        int known = 0;
        for (int k = 0; k < count; k++) known |= strcmp(seen[k], path) == 0;
        if (!known && count < 8) snprintf(seen[count++], sizeof seen[0], "%s", path);
    }
    if (!maps) return -1;
    fclose(maps);
    return count;
#endif
}

/* The environment (and on Linux the handlers of SIGNALS), as one comparable record. Windows has no
 * sigaction: a signal() handler lives in the table of whichever C runtime installed it (the FMU's DLL may
 * have its own) and cannot be read without being replaced, and console control handlers cannot be listed;
 * so on Windows the record, and the host's "host-unchanged", is the environment only. */
typedef struct {
    char environment[65536];
#ifndef _WIN32
    struct sigaction actions[N_SIGNALS];
#endif
} host_state;

/* Append `entry` and a newline to the record's environment (cut where it is full, as it always was). */
static inline void record_variable(host_state *state, const char *entry) {
    strncat(state->environment, entry, sizeof state->environment - strlen(state->environment) - 2);
    strcat(state->environment, "\n");
}

static inline void snapshot(host_state *state) {
    memset(state, 0, sizeof *state);
#ifdef _WIN32
    /* the process's own environment block, which SetEnvironmentVariable and every C runtime's putenv
     * change, not this host's C runtime's copy of it */
    wchar_t *block = GetEnvironmentStringsW();
    for (const wchar_t *e = block; e && *e; e += wcslen(e) + 1) {
        char *entry = utf8_from_wide(e);
        record_variable(state, entry ? entry : "(not UTF-16)");
        free(entry);
    }
    if (block) FreeEnvironmentStringsW(block);
#else
    for (char **e = environ; *e; e++) record_variable(state, *e);
    for (size_t k = 0; k < N_SIGNALS; k++) sigaction(SIGNALS[k], NULL, &state->actions[k]);
#endif
}

static inline int unchanged(const host_state *before, const host_state *after) {
    if (strcmp(before->environment, after->environment) != 0) return 0;
#ifndef _WIN32
    for (size_t k = 0; k < N_SIGNALS; k++)
        if (before->actions[k].sa_handler != after->actions[k].sa_handler) return 0;
#endif
    return 1;
}

/* -------------------------------------------------------------------------------- arguments and inputs */

#define MAX_ARGS 128

/* One argument of a host: K:VR=VALUE (K: r Float64/Real start value, b Boolean 0|1, s String, i input),
 * j:VR=VALUE@T (an input's jump at T, FMI 3 host only), o:VR (an output to print at the end), O:VR (an
 * output to print at every communication point), e:N (the O: outputs printed at every N-th step's end
 * only, FMI 3 host only; N in `vr`), c:N (the run N times over, instantiation to free, printing the
 * memory; N in `vr`), l:0|1 (loggingOn; in `vr`) or f:PATH (an input table, read_input_table). */
typedef struct {
    char kind;
    unsigned int vr;
    double real; /* VALUE as a number */
    const char *text; /* VALUE as text */
    double at;   /* T of a jump */
} host_argument;

/* Parse `text` into `a`; 0 if it is malformed. */
static inline int parse_argument(const char *text, host_argument *a) {
    const char *value = strchr(text, '='), *at = value ? strchr(value, '@') : NULL;
    *a = (host_argument){text[0], (unsigned int)strtoul(text + 2, NULL, 10), value ? atof(value + 1) : 0.0,
                         value ? value + 1 : "", at ? atof(at + 1) : 0.0};
    if (text[0] == '\0' || text[1] != ':') return 0;
    if (strchr("oOecl", a->kind)) return 1;
    if (a->kind == 'f') return a->text = text + 2, 1;
    return value && strchr("rbsij", a->kind) && (a->kind != 'j' || at);
}

/* An input table: a CSV file whose first line is "time,VR,VR,..." (value references) and whose rows are
 * numbers; the inputs at time t are interpolated linearly between rows, held before the first and after
 * the last (as the FMI Compliance Checker and fmpy read an _in.csv). */
#define MAX_ROWS 20000
typedef struct {
    size_t n_columns, n_rows;
    unsigned int vr[MAX_ARGS];
    double *rows; /* n_rows x (1 + n_columns): time, values */
} input_table;

/* Read `path` (UTF-8) into `table`; 0 if it cannot be read or is malformed. */
static inline int read_input_table(const char *path, input_table *table) {
    FILE *file = open_file(path, "r");
    if (!file) return 0;
    char line[65536];
    memset(table, 0, sizeof *table);
    if (!fgets(line, sizeof line, file) || strncmp(line, "time", 4) != 0) return fclose(file), 0;
    for (char *field = strchr(line, ','); field && table->n_columns < MAX_ARGS; field = strchr(field + 1, ','))
        table->vr[table->n_columns++] = (unsigned int)strtoul(field + 1, NULL, 10);
    table->rows = malloc(sizeof(double) * MAX_ROWS * (1 + table->n_columns));
    while (table->rows && table->n_rows < MAX_ROWS && fgets(line, sizeof line, file)) {
        char *at = line;
        double *row = table->rows + table->n_rows * (1 + table->n_columns);
        for (size_t k = 0; k <= table->n_columns; k++) {
            char *end;
            row[k] = strtod(at, &end);
            if (end == at) return fclose(file), 0;
            at = *end == ',' ? end + 1 : end;
        }
        table->n_rows++;
    }
    fclose(file);
    return table->rows && table->n_rows > 0;
}

/* The table's values at time `t` into `values` (one per column), in fmpy's arithmetic (Input.interpolate:
 * w0 = (t1 - t) / (t1 - t0), v = w0 v0 + (1 - w0) v1). */
static inline void interpolate_inputs(const input_table *table, double t, double *values) {
    size_t width = 1 + table->n_columns, k = 0;
    const double *rows = table->rows;
    while (k < table->n_rows && rows[k * width] < t) k++; /* the first row at or after t */
    if (k == 0 || k == table->n_rows) {                  /* hold the first or the last row */
        const double *held = rows + (k == 0 ? 0 : table->n_rows - 1) * width;
        for (size_t c = 0; c < table->n_columns; c++) values[c] = held[1 + c];
        return;
    }
    const double *a = rows + (k - 1) * width, *b = rows + k * width;
    double w0 = (b[0] - t) / (b[0] - a[0]), w1 = 1 - w0;
    for (size_t c = 0; c < table->n_columns; c++) values[c] = w0 * a[1 + c] + w1 * b[1 + c];
}

/* Return 5 from the calling function if an FMI call fails (a status above Warning). */
#define CHECK(call)                                                                                               \
    do {                                                                                                          \
        int status_ = (int)(call);                                                                                \
        if (status_ > 1) {                                                                                        \
            fprintf(stderr, "%s failed with status %d\n", #call, status_);                                       \
            return 5;                                                                                             \
        }                                                                                                         \
    } while (0)

#endif
