/* The C half of the bridge to the FMU's Python side (see bridge.h). */
#define _GNU_SOURCE
#include "glibc_compat.h"

#include "bridge.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "text.h"

#define PY_FILE_INPUT 257 /* Py_file_input */

/* Load the FMU's package `package` and its entry module `entry` from the zip resources/<archive> (the FMU's code,
 * fmu/build/bundle.py) under their own (private) names, once per process, and take the entry's bridge.  The zip is
 * read by the package's archive_import (fmu_src/archive_import.py, itself read with zipimport), registered for the
 * zip's own paths in sys.path_importer_cache, and so is the zipped standard library of the CPython this FMU carries
 * where that is the process's Python (`stdlib`: its path, else empty).  The folder's path crosses as bytes
 * (os.fsdecode: it names the same folder whatever the file system encoding of a Python host).  Nothing is put on
 * sys.path; the modules stay in sys.modules, so an FMU unloaded and loaded again, or extracted again elsewhere,
 * finds them there and reads no zip.  One thread at a time loads (the lock lives in sys.modules, shared by every FMU
 * of this project): another sees a module only once it is complete. */
static const char BOOTSTRAP[] =
    "import os, sys, threading, types, zipimport\n"
    "resources = os.fsdecode(resources)  # the folder's bytes, whatever the file system encoding\n"
    "path = os.path.join(resources, archive)\n"
    "loading = sys.modules.setdefault('_dp_fmu_loading', types.ModuleType('_dp_fmu_loading'))\n"
    "with vars(loading).setdefault('lock', threading.RLock()):\n"
    "    missing = [name for name in (package, entry) if name not in sys.modules]\n"
    "    if missing:\n"
    "        importer = vars(loading).get(package)\n"
    "        if importer is None:  # archive_import, run from the zip without being imported\n"
    "            importer = {'__name__': package + '.archive_import'}\n"
    "            exec(zipimport.zipimporter(os.path.join(path, package)).get_code('archive_import'), importer)\n"
    "            vars(loading)[package] = importer\n"
    "        finders = vars(loading).setdefault('finders', {})\n"
    "        for zip_path in (path, os.fsdecode(stdlib)) if stdlib else (path,):\n"
    "            if zip_path not in finders:\n"
    "                finders[zip_path] = importer['install'](zip_path)\n"
    "        import importlib.util\n"
    "        for name in missing:\n"
    "            spec = finders[path].find_spec(name)\n"
    "            if spec is None:\n"
    "                raise ImportError(f'{name} is not in {path}')\n"
    "            module = importlib.util.module_from_spec(spec)\n"
    "            sys.modules[name] = module\n"
    "            try:\n"
    "                spec.loader.exec_module(module)\n"
    "            except BaseException:\n"
    "                del sys.modules[name]\n"
    "                raise\n"
    "    bridge = sys.modules[entry].fmi_bridge\n";

/* ----------------------------------------------------------------------------- messages */

typedef struct {
    int status;
    char *category, *text;
} message;

typedef struct {
    message *items;
    size_t n, capacity;
    char failure[1024]; /* what went wrong in the bridge itself ("" if nothing) */
    int interrupted;
    PyObject *host; /* the redelivery of the host's own exception that stopped the call (a reference), or NULL */
} answer_notes;

static void note_failure(answer_notes *notes, const char *format, ...) __attribute__((format(printf, 2, 3)));
static void note_failure(answer_notes *notes, const char *format, ...) {
    if (notes->failure[0]) return; /* the first one says it */
    char text[sizeof notes->failure];
    va_list args;
    va_start(args, format);
    int n = vsnprintf(text, sizeof text, format, args);
    va_end(args);
    text_format(notes->failure, sizeof notes->failure, "%s", n >= 0 ? text : "unknown failure");
}

/* A KeyboardInterrupt stopped the call, wherever it landed (in the Python side's code, or before or around it):
 * one text for every case, which docs/fmu.md quotes, in place of any other failure. */
static void note_interrupt(answer_notes *notes) {
    notes->interrupted = 1;
    text_format(notes->failure, sizeof notes->failure, "%s", BRIDGE_INTERRUPTED_TEXT);
}

static void add_message(answer_notes *notes, int status, const char *category, const char *text) {
    if (notes->n == notes->capacity) {
        size_t capacity = notes->capacity ? 2 * notes->capacity : 4;
        message *items = realloc(notes->items, capacity * sizeof *items);
        if (!items) return note_failure(notes, "out of memory for the FMU's messages");
        notes->items = items, notes->capacity = capacity;
    }
    message *m = &notes->items[notes->n];
    m->status = status;
    m->category = strdup(category ? category : "");
    m->text = strdup(text ? text : "");
    if (!m->category || !m->text) {
        free(m->category), free(m->text);
        return note_failure(notes, "out of memory for the FMU's messages");
    }
    notes->n++;
}

/* Give the messages to the host's logger (no lock held: the GIL is released) and free them. */
static void emit_notes(guard_instance *g, answer_notes *notes) {
    for (size_t k = 0; k < notes->n; k++) {
        message *m = &notes->items[k];
        char line[4200];
        int status = m->status < STATUS_OK || m->status > STATUS_ERROR ? STATUS_ERROR : m->status;
        if (status >= STATUS_DISCARD)
            text_format(line, sizeof line, "%s: %s", g->function ? g->function : "FMU", m->text);
        else
            text_format(line, sizeof line, "%s", m->text);
        guard_emit(g, status, m->category, line);
        free(m->category), free(m->text);
    }
    free(notes->items);
    notes->items = NULL, notes->n = notes->capacity = 0;
    if (notes->failure[0]) {
        char line[sizeof notes->failure + 200];
        text_format(line, sizeof line, "%s: %s", g->function ? g->function : "FMU", notes->failure);
        guard_emit(g, STATUS_ERROR, "logStatusError", line);
    }
}

/* ----------------------------------------------------------------------------- with the GIL */

/* Python's Py_BuildValue through the API table. */
static PyObject *build(const python_api *py, const char *format, ...) {
    va_list args;
    va_start(args, format);
    PyObject *built = py->VaBuildValue(format, args);
    va_end(args);
    return built;
}

/* The answer of the call that exception `value` escaped, if it is the host's own (target.escaped_answer:
 * fmi_bridge.py, which writes its line and its redelivery), else NULL. */
static PyObject *escaped_answer(const python_api *py, PyObject *target, PyObject *value) {
    PyObject *ask = target && value ? py->Object_GetAttrString(target, "escaped_answer") : NULL;
    PyObject *arguments = ask ? build(py, "(O)", value) : NULL;
    PyObject *answer = arguments ? py->Object_Call(ask, arguments, NULL) : NULL;
    if (arguments) py->DecRef(arguments);
    if (ask) py->DecRef(ask);
    py->Err_Clear(); /* a failure to ask: the exception is said as the FMU's */
    if (answer && answer == py->None) py->DecRef(answer), answer = NULL;
    return answer;
}

static int take_answer(const python_api *py, PyObject *answer, bridge_payload payload, answer_notes *notes,
                       const char *method);

/* The pending Python exception in words ("ValueError: ..."), cleared; notes a KeyboardInterrupt, and takes the
 * answer `target` gives for the host's own exception (NULL: none is asked) as the call's. An exception escapes a call
 * of the Python side only before its answer is made: a signal handler of the host runs as a Python function starts. */
static void take_exception(const python_api *py, answer_notes *notes, const char *what, PyObject *target) {
    if (!py->Err_Occurred()) return note_failure(notes, "%s failed without saying why", what);
    PyObject *type = NULL, *value = NULL, *traceback = NULL;
    py->Err_Fetch(&type, &value, &traceback);
    py->Err_NormalizeException(&type, &value, &traceback);
    if (value && traceback) py->Exception_SetTraceback(value, traceback);
    py->Err_Clear();
    PyObject *name = type ? py->Object_GetAttrString(type, "__name__") : NULL;
    PyObject *text = value ? py->Object_Str(value) : NULL;
    const char *name_text = name ? py->Unicode_AsUTF8AndSize(name, NULL) : NULL;
    const char *value_text = text ? py->Unicode_AsUTF8AndSize(text, NULL) : NULL;
    py->Err_Clear(); /* whatever describing it raised */
    int interrupt = name_text && strcmp(name_text, "KeyboardInterrupt") == 0;
    PyObject *host = interrupt ? NULL : escaped_answer(py, target, value);
    if (interrupt) note_interrupt(notes);
    else if (host) take_answer(py, host, NO_PAYLOAD, notes, what), py->DecRef(host);
    else note_failure(notes, "%s raised %s: %s", what, name_text ? name_text : "an exception",
                      value_text && value_text[0] ? value_text : "(no message)");
    if (name) py->DecRef(name);
    if (text) py->DecRef(text);
    if (type) py->DecRef(type);
    if (value) py->DecRef(value);
    if (traceback) py->DecRef(traceback);
}

/* A str item of a tuple, as UTF-8 (borrowed from the object), or NULL (no exception left). */
static const char *text_item(const python_api *py, PyObject *tuple, ssize_t k) {
    PyObject *item = py->Tuple_GetItem(tuple, k);
    const char *text = item ? py->Unicode_AsUTF8AndSize(item, NULL) : NULL;
    if (!text) py->Err_Clear();
    return text;
}

/* Read the answer (status, payload, messages) into `payload` and `notes`; returns the status. */
static int take_answer(const python_api *py, PyObject *answer, bridge_payload payload, answer_notes *notes,
                       const char *method) {
    if (py->Tuple_Size(answer) != 3) {
        py->Err_Clear();
        note_failure(notes, "the FMU's Python side answered %s with something that is not (status, payload, "
                            "messages)", method);
        return STATUS_ERROR;
    }
    long status = py->Long_AsLong(py->Tuple_GetItem(answer, 0));
    if (status == -1 && py->Err_Occurred()) py->Err_Clear(), status = STATUS_ERROR;
    PyObject *messages = py->Tuple_GetItem(answer, 2);
    ssize_t n = messages ? py->Tuple_Size(messages) : -1;
    for (ssize_t k = 0; k < n; k++) {
        PyObject *m = py->Tuple_GetItem(messages, k);
        long level = m && py->Tuple_Size(m) == 3 ? py->Long_AsLong(py->Tuple_GetItem(m, 0)) : -1;
        const char *category = level >= 0 ? text_item(py, m, 1) : NULL;
        const char *text = category ? text_item(py, m, 2) : NULL;
        if (text) add_message(notes, (int)level, category, text);
        else py->Err_Clear(), note_failure(notes, "the FMU's Python side gave a malformed message");
    }
    if (n < 0) py->Err_Clear();
    if (status == BRIDGE_INTERRUPTED) {
        note_interrupt(notes);
        return STATUS_ERROR;
    }
    if (status == BRIDGE_HOST) { /* its line is among the messages */
        PyObject *redelivery = py->Tuple_GetItem(answer, 1);
        if (redelivery) py->IncRef(redelivery), notes->host = redelivery;
        else py->Err_Clear();
        return STATUS_ERROR;
    }
    if (status < STATUS_OK || status > STATUS_ERROR) status = STATUS_ERROR;
    if (status > STATUS_WARNING || payload.kind == PAYLOAD_NONE) return (int)status;
    PyObject *value = py->Tuple_GetItem(answer, 1);
    if (payload.kind == PAYLOAD_OBJECT) {
        py->IncRef(value);
        *payload.object = value;
        return (int)status;
    }
    char *bytes = NULL;
    ssize_t size = 0;
    if (!value || py->Bytes_AsStringAndSize(value, &bytes, &size) != 0) {
        py->Err_Clear();
        note_failure(notes, "the FMU's Python side answered %s without bytes", method);
        return STATUS_ERROR;
    }
    if (payload.kind == PAYLOAD_EXACT) {
        if ((size_t)size != payload.size) {
            note_failure(notes, "the FMU's Python side answered %s with %zd bytes, not %zu", method, size,
                         payload.size);
            return STATUS_ERROR;
        }
        if (size) memcpy(payload.buffer, bytes, (size_t)size);
        return (int)status;
    }
    char *copy = malloc((size_t)size + 1);
    if (!copy) {
        note_failure(notes, "out of memory (%zd bytes)", size);
        return STATUS_ERROR;
    }
    memcpy(copy, bytes, (size_t)size);
    copy[size] = '\0';
    *payload.copy = copy, *payload.copy_size = (size_t)size;
    return (int)status;
}

/* Call target.method(*arguments) with the GIL, then log what it said without it. */
static int call_object(guard_instance *g, PyObject *target, bridge_payload payload, const char *method,
                       const char *format, va_list args) {
    const python_api *py = g->api;
    answer_notes notes = {0};
    int gil = python_runtime_take_gil();
    PyObject *arguments = py->VaBuildValue(format, args);
    PyObject *callable = arguments ? py->Object_GetAttrString(target, method) : NULL;
    PyObject *answer = callable ? py->Object_Call(callable, arguments, NULL) : NULL;
    int status = STATUS_ERROR;
    if (answer) status = take_answer(py, answer, payload, &notes, method);
    else take_exception(py, &notes, method, target);
    if (answer) py->DecRef(answer);
    if (callable) py->DecRef(callable);
    if (arguments) py->DecRef(arguments);
    if (notes.host) { /* the latest one is raised again (a call the logger makes may have stopped one before) */
        if (g->host_exception) py->DecRef(g->host_exception);
        g->host_exception = notes.host, status = STATUS_ERROR;
    }
    py->GILState_Release(gil);
    if (notes.interrupted) {
        g->interrupted = 1; /* raised again for the host when the FMI function returns (guard_deliver_interrupt) */
        status = STATUS_ERROR;
    }
    emit_notes(g, &notes);
    return status;
}

int bridge_call(guard_instance *g, bridge_payload payload, const char *method, const char *format, ...) {
    va_list args;
    va_start(args, format);
    int status = call_object(g, g->python, payload, method, format, args);
    va_end(args);
    return status;
}

static int call_bridge(guard_instance *g, PyObject *bridge, bridge_payload payload, const char *format, ...) {
    va_list args;
    va_start(args, format);
    int status = call_object(g, bridge, payload, "instantiate", format, args);
    va_end(args);
    return status;
}

int bridge_instantiate(guard_instance *g, const python_api *py, const char *resources, const char *archive,
                       const char *package, const char *entry, const char *interface, int visible,
                       PyObject **instance) {
    g->api = py;
    answer_notes notes = {0};
    int gil = python_runtime_take_gil();
    PyObject *globals = py->Dict_New();
    PyObject *resources_text = py->Bytes_FromStringAndSize(resources, (ssize_t)strlen(resources));
    PyObject *entry_text = py->Unicode_FromString(entry);
    PyObject *package_text = py->Unicode_FromString(package);
    PyObject *archive_text = py->Unicode_FromString(archive);
    const char *carried = python_runtime_stdlib();
    PyObject *stdlib_text = py->Bytes_FromStringAndSize(carried, (ssize_t)strlen(carried));
    PyObject *code = py->CompileString(BOOTSTRAP, "<double-pendulum-fmu loader>", PY_FILE_INPUT);
    PyObject *bridge = NULL;
    if (globals && resources_text && entry_text && package_text && archive_text && stdlib_text && code &&
        py->Dict_SetItemString(globals, "resources", resources_text) == 0 &&
        py->Dict_SetItemString(globals, "archive", archive_text) == 0 &&
        py->Dict_SetItemString(globals, "stdlib", stdlib_text) == 0 &&
        py->Dict_SetItemString(globals, "package", package_text) == 0 &&
        py->Dict_SetItemString(globals, "entry", entry_text) == 0) {
        PyObject *done = py->Eval_EvalCode(code, globals, globals);
        if (done) {
            py->DecRef(done);
            bridge = py->Dict_GetItemString(globals, "bridge");
            if (bridge) py->IncRef(bridge);
        }
    }
    if (!bridge) take_exception(py, &notes, "loading the FMU's Python code", NULL);
    if (globals) py->Dict_Clear(globals), py->DecRef(globals); /* no cycle through the module's namespace */
    if (code) py->DecRef(code);
    if (entry_text) py->DecRef(entry_text);
    if (package_text) py->DecRef(package_text);
    if (archive_text) py->DecRef(archive_text);
    if (stdlib_text) py->DecRef(stdlib_text);
    if (resources_text) py->DecRef(resources_text);
    py->GILState_Release(gil);
    if (!bridge) {
        emit_notes(g, &notes);
        return STATUS_ERROR;
    }
    bridge_payload payload = {PAYLOAD_OBJECT, NULL, 0, NULL, NULL, instance};
    int status = call_bridge(g, bridge, payload, "(y#ssi)", resources, (ssize_t)strlen(resources), g->name,
                             interface, visible);
    bridge_release(g, bridge);
    return status;
}

void bridge_release(guard_instance *g, PyObject *object) {
    if (!object) return;
    int gil = python_runtime_take_gil();
    g->api->DecRef(object);
    g->api->GILState_Release(gil);
}

void bridge_deliver_host_exception(guard_instance *g) {
    PyObject *redelivery = g->host_exception;
    if (!redelivery) return;
    g->host_exception = NULL;
    const python_api *py = g->api;
    int python_thread = py->GILState_GetThisThreadState() != NULL; /* before Ensure, which makes one */
    int gil = python_runtime_take_gil();
    if (python_thread) py->ThreadState_SetAsyncExc(py->Thread_get_thread_ident(), redelivery);
    py->DecRef(redelivery);
    py->GILState_Release(gil);
}
