/* The loader's platform layer (see platform.h): the POSIX half, then the Windows half. */
#ifndef _WIN32
#define _GNU_SOURCE
#include "glibc_compat.h"
#endif

#include "platform.h"

#include "text.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>

void platform_parent_folder(char *path) {
    char *slash = NULL;
    for (char *p = path; *p; p++)
        if (platform_is_separator(*p)) slash = p;
    if (slash == path) slash[1] = '\0';
    else if (slash) *slash = '\0';
}

#ifndef _WIN32
/* ============================================================================== POSIX */

#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <link.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

extern char **environ;


void platform_lock(platform_mutex *mutex) { pthread_mutex_lock(mutex); }
void platform_unlock(platform_mutex *mutex) { pthread_mutex_unlock(mutex); }

/* stderr's lock: libc's, shared by every library in the process */
void platform_lock_process(void) { flockfile(stderr); }
void platform_unlock_process(void) { funlockfile(stderr); }

int platform_is_directory(const char *path) {
    int fd = open(path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return 0;
    close(fd);
    return 1;
}

int platform_is_file(const char *path) {
    if (access(path, R_OK) != 0) return 0;
    int fd = open(path, O_RDONLY | O_DIRECTORY | O_CLOEXEC); /* no stat: see glibc_compat.h */
    if (fd >= 0) {
        close(fd);
        return 0;
    }
    return errno == ENOTDIR;
}

FILE *platform_open_text(const char *path) { return fopen(path, "re"); }

void platform_uri_path(char *path) { (void)path; }

int platform_is_separator(char c) { return c == '/'; }

int platform_own_folder(char *folder, size_t size) {
    Dl_info info;
    char resolved[PATH_MAX];
    if (!dladdr((void *)&platform_own_folder, &info) || !info.dli_fname || !realpath(info.dli_fname, resolved))
        return 0;
    platform_parent_folder(resolved);
    return text_fits(folder, size, "%s", resolved);
}

int platform_at_fork(void (*prepare)(void), void (*parent)(void), void (*child)(void)) {
    return pthread_atfork(prepare, parent, child) == 0; /* glibc drops them when this library is unloaded */
}

unsigned long platform_thread_self(void) { return (unsigned long)pthread_self(); }

void platform_pin_self(void) {
    Dl_info info;
    if (dladdr((void *)&platform_pin_self, &info) && info.dli_fname)
        dlopen(info.dli_fname, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE); /* never unloaded from now on */
}

const char *platform_getenv(const char *name, char *buffer, size_t size) {
    const char *value = getenv(name);
    return value && text_fits(buffer, size, "%s", value) ? buffer : NULL;
}

void *platform_load(const char *path, char *why, size_t size) {
    void *library = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!library) text_format(why, size, "cannot be loaded: %s", dlerror());
    return library;
}

void *platform_make_global(const char *path, void *library, char *why, size_t size) {
    (void)library;
    void *global = dlopen(path, RTLD_NOW | RTLD_NOLOAD | RTLD_GLOBAL); /* the same copy, global */
    if (!global) text_format(why, size, "cannot be made global: %s", dlerror());
    return global;
}

void *platform_symbol(void *library, const char *name) { return dlsym(library, name); }

void platform_unload(void *library) {
    if (library && library != RTLD_DEFAULT) dlclose(library);
}

static int find_loaded_libpython(struct dl_phdr_info *info, size_t size, void *data) {
    (void)size;
    const char *name = strrchr(info->dlpi_name, '/');
    name = name ? name + 1 : info->dlpi_name;
    if (strncmp(name, "libpython3", 10) != 0) return 0;
    return text_fits((char *)data, PATH_MAX, "%s", info->dlpi_name);
}

/* The interpreter of a Python host (libpython, or a python executable exporting its symbols), or a
 * libpython loaded privately, which is then made global (RTLD_NOLOAD: no second copy). */
int platform_loaded_python(void **library, char *path, size_t size) {
    void *initialized = dlsym(RTLD_DEFAULT, "Py_IsInitialized");
    if (!initialized) {
        char loaded[PATH_MAX] = "";
        dl_iterate_phdr(find_loaded_libpython, loaded);
        if (!loaded[0] || !dlopen(loaded, RTLD_NOW | RTLD_NOLOAD | RTLD_GLOBAL)) return 0;
        initialized = dlsym(RTLD_DEFAULT, "Py_IsInitialized");
        if (!initialized) return 0;
    }
    Dl_info info;
    if (!dladdr(initialized, &info) || !info.dli_fname || !text_fits(path, size, "%s", info.dli_fname)) path[0] = '\0';
    *library = RTLD_DEFAULT;
    return 1;
}

int platform_which(const char *name, char *found, size_t size) {
    if (strchr(name, '/')) return text_fits(found, size, "%s", name) && access(found, X_OK) == 0;
    const char *path = getenv("PATH");
    if (!path) return 0;
    for (const char *start = path; *start;) {
        const char *end = strchr(start, ':');
        size_t length = end ? (size_t)(end - start) : strlen(start);
        if (text_fits(found, size, "%.*s/%s", (int)length, length ? start : ".", name) && access(found, X_OK) == 0 &&
            platform_is_file(found))
            return 1;
        if (!end) break;
        start = end + 1;
    }
    return 0;
}

/* Read what the child writes to `fd` until it closes it or `deadline` (CLOCK_MONOTONIC ms) passes. */
static int read_until(int fd, char *output, size_t size, long deadline, int timeout_ms, char *why, size_t why_size) {
    size_t used = 0;
    for (;;) {
        struct timespec now;
        clock_gettime(CLOCK_MONOTONIC, &now);
        long left = deadline - (now.tv_sec * 1000L + now.tv_nsec / 1000000L);
        if (left <= 0) {
            text_format(why, why_size, "did not answer within %d s", timeout_ms / 1000);
            return 0;
        }
        struct pollfd ready = {fd, POLLIN, 0};
        int polled = poll(&ready, 1, (int)left);
        if (polled < 0 && errno == EINTR) continue;
        if (polled < 0) {
            text_format(why, why_size, "cannot be read from (poll: %s)", strerror(errno));
            return 0;
        }
        if (polled == 0) continue; /* the deadline check above ends it */
        ssize_t got = read(fd, output + used, size - 1 - used);
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) {
            text_format(why, why_size, "cannot be read from (read: %s)", strerror(errno));
            return 0;
        }
        if (got == 0) break;
        used += (size_t)got;
        if (used + 1 >= size) break;
    }
    output[used] = '\0';
    return 1;
}

int platform_run(char *const argv[], char *output, size_t size, int timeout_ms, char *why, size_t why_size) {
    int pipe_fds[2];
    if (pipe2(pipe_fds, O_CLOEXEC) != 0) {
        text_format(why, why_size, "cannot ask it (pipe: %s)", strerror(errno));
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
    pid_t pid = -1;
    if (!failed) failed = posix_spawn(&pid, argv[0], &actions, &attributes, argv, environ);
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attributes);
    close(pipe_fds[1]);
    if (failed) {
        close(pipe_fds[0]);
        text_format(why, why_size, "cannot run it (%s)", strerror(failed));
        return 0;
    }
    struct timespec start;
    clock_gettime(CLOCK_MONOTONIC, &start);
    int answered = read_until(pipe_fds[0], output, size, start.tv_sec * 1000L + start.tv_nsec / 1000000L + timeout_ms,
                              timeout_ms, why, why_size);
    close(pipe_fds[0]);
    kill(-pid, SIGKILL); /* the group: whatever it started and left (the leader itself may have ended) */
    int status = 0;
    pid_t waited;
    while ((waited = waitpid(pid, &status, 0)) < 0 && errno == EINTR) {
    }
    if (!answered) return 0;
    /* waitpid fails (ECHILD) where the host ignores SIGCHLD or reaps every child itself: the answer stands */
    if (waited == pid && WIFEXITED(status) && WEXITSTATUS(status) != 0) {
        text_format(why, why_size, "ended with exit status %d", WEXITSTATUS(status));
        return 0;
    }
    return 1;
}

#else
/* ============================================================================ Windows */

#define WIN32_LEAN_AND_MEAN
#include <windows.h>
#include <psapi.h>
#include <wchar.h>

/* `text` (UTF-8) as a new UTF-16 string, NULL if it is not UTF-8 or memory is short. */
static wchar_t *wide(const char *text) {
    int n = MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, text, -1, NULL, 0);
    wchar_t *out = n > 0 ? malloc((size_t)n * sizeof *out) : NULL;
    if (out && MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, text, -1, out, n) != n) {
        free(out);
        out = NULL;
    }
    return out;
}

/* `text` (UTF-16) as UTF-8 in `out`; 0 if it does not fit. */
static int narrow(const wchar_t *text, char *out, size_t size) {
    int n = WideCharToMultiByte(CP_UTF8, 0, text, -1, out, (int)(size < INT_MAX ? size : INT_MAX), NULL, NULL);
    return n > 0;
}

void platform_lock(platform_mutex *mutex) { AcquireSRWLockExclusive((PSRWLOCK)&mutex->opaque); }
void platform_unlock(platform_mutex *mutex) { ReleaseSRWLockExclusive((PSRWLOCK)&mutex->opaque); }

/* A mutex named after the process: every copy of the loader in it opens the same one. */
static HANDLE process_mutex;

void platform_lock_process(void) {
    wchar_t name[64];
    swprintf(name, sizeof name / sizeof *name, L"Local\\double-pendulum-fmu-python-%lu", GetCurrentProcessId());
    HANDLE mutex = CreateMutexW(NULL, FALSE, name);
    if (mutex && WaitForSingleObject(mutex, INFINITE) == WAIT_FAILED) {
        CloseHandle(mutex);
        mutex = NULL;
    }
    process_mutex = mutex; /* held: no other thread of this copy writes it until the unlock */
}

void platform_unlock_process(void) {
    HANDLE mutex = process_mutex;
    process_mutex = NULL;
    if (!mutex) return;
    ReleaseMutex(mutex);
    CloseHandle(mutex);
}

static DWORD attributes(const char *path) {
    wchar_t *w = wide(path);
    DWORD found = w ? GetFileAttributesW(w) : INVALID_FILE_ATTRIBUTES;
    free(w);
    return found;
}

int platform_is_directory(const char *path) {
    DWORD a = attributes(path);
    return a != INVALID_FILE_ATTRIBUTES && (a & FILE_ATTRIBUTE_DIRECTORY);
}

int platform_is_file(const char *path) {
    DWORD a = attributes(path);
    return a != INVALID_FILE_ATTRIBUTES && !(a & FILE_ATTRIBUTE_DIRECTORY);
}

FILE *platform_open_text(const char *path) {
    wchar_t *w = wide(path);
    FILE *file = w ? _wfopen(w, L"rN") : NULL; /* N: not inherited */
    free(w);
    return file;
}

void platform_uri_path(char *path) {
    /* file:///C:/x gives /C:/x: the drive letter starts the path */
    if (path[0] == '/' && ((path[1] >= 'A' && path[1] <= 'Z') || (path[1] >= 'a' && path[1] <= 'z')) &&
        path[2] == ':')
        memmove(path, path + 1, strlen(path));
}

int platform_is_separator(char c) { return c == '/' || c == '\\'; }

/* Windows has no fork: nothing to register, nothing to pin. */
int platform_at_fork(void (*prepare)(void), void (*parent)(void), void (*child)(void)) {
    (void)prepare, (void)parent, (void)child;
    return 1;
}

void platform_pin_self(void) {}

unsigned long platform_thread_self(void) { return GetCurrentThreadId(); }

int platform_own_folder(char *folder, size_t size) {
    HMODULE self = NULL;
    wchar_t path[PLATFORM_PATH_MAX];
    if (!GetModuleHandleExW(GET_MODULE_HANDLE_EX_FLAG_FROM_ADDRESS | GET_MODULE_HANDLE_EX_FLAG_UNCHANGED_REFCOUNT,
                            (LPCWSTR)(void *)&platform_own_folder, &self))
        return 0;
    DWORD n = GetModuleFileNameW(self, path, PLATFORM_PATH_MAX);
    if (n == 0 || n >= PLATFORM_PATH_MAX || !narrow(path, folder, size)) return 0;
    platform_parent_folder(folder);
    return 1;
}

const char *platform_getenv(const char *name, char *buffer, size_t size) {
    wchar_t *w = wide(name), value[PLATFORM_PATH_MAX];
    DWORD n = w ? GetEnvironmentVariableW(w, value, PLATFORM_PATH_MAX) : 0;
    free(w);
    return n > 0 && n < PLATFORM_PATH_MAX && narrow(value, buffer, size) ? buffer : NULL;
}

void *platform_load(const char *path, char *why, size_t size) {
    wchar_t *w = wide(path);
    if (!w) {
        text_format(why, size, "cannot be loaded: its path is not UTF-8");
        return NULL;
    }
    DWORD mode = 0; /* no error box for this thread while it loads; the thread's mode is restored */
    BOOL quiet = SetThreadErrorMode(SEM_FAILCRITICALERRORS | SEM_NOOPENFILEERRORBOX, &mode);
    /* the DLL's own folder first for the DLLs it needs (vcruntime140.dll beside python3X.dll) */
    HMODULE library = LoadLibraryExW(w, NULL, LOAD_WITH_ALTERED_SEARCH_PATH);
    DWORD error = GetLastError();
    if (quiet) SetThreadErrorMode(mode, NULL);
    free(w);
    if (!library) text_format(why, size, "cannot be loaded (LoadLibraryExW: Windows error %lu)", error);
    return library;
}

void *platform_make_global(const char *path, void *library, char *why, size_t size) {
    (void)path, (void)why, (void)size;
    return library; /* no global scope: the extension modules link python3X.dll by name, already loaded */
}

void *platform_symbol(void *library, const char *name) {
    return library ? (void *)GetProcAddress((HMODULE)library, name) : NULL;
}

void platform_unload(void *library) {
    if (library) FreeLibrary((HMODULE)library);
}

/* "python3X.dll" or "python3XY.dll" (not python3.dll, the stable ABI's forwarder), any case. */
static int is_python_dll(const wchar_t *name) {
    if (_wcsnicmp(name, L"python3", 7) != 0) return 0;
    const wchar_t *digits = name + 7;
    size_t n = 0;
    while (digits[n] >= L'0' && digits[n] <= L'9') n++;
    return n >= 1 && n <= 3 && _wcsicmp(digits + n, L".dll") == 0;
}

int platform_loaded_python(void **library, char *path, size_t size) {
    HMODULE modules[1024];
    DWORD needed = 0;
    if (!K32EnumProcessModules(GetCurrentProcess(), modules, sizeof modules, &needed)) return 0;
    size_t n = needed / sizeof *modules;
    for (size_t k = 0; k < n && k < sizeof modules / sizeof *modules; k++) {
        wchar_t file[PLATFORM_PATH_MAX];
        DWORD length = GetModuleFileNameW(modules[k], file, PLATFORM_PATH_MAX);
        if (length == 0 || length >= PLATFORM_PATH_MAX) continue;
        const wchar_t *base = file + length;
        while (base > file && base[-1] != L'\\' && base[-1] != L'/') base--;
        if (!is_python_dll(base) || !GetProcAddress(modules[k], "Py_IsInitialized")) continue;
        if (!narrow(file, path, size)) path[0] = '\0';
        *library = modules[k]; /* the process's own reference: never given back */
        return 1;
    }
    return 0;
}

int platform_which(const char *name, char *found, size_t size) {
    (void)name, (void)found, (void)size;
    return 0; /* the loader never searches for a program on Windows */
}

int platform_run(char *const argv[], char *output, size_t size, int timeout_ms, char *why, size_t why_size) {
    (void)argv, (void)size, (void)timeout_ms;
    output[0] = '\0';
    text_format(why, why_size, "is not run: on Windows the FMU does not ask a program about itself");
    return 0;
}

#endif
