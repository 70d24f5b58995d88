/* The Python bridge: the FMI 2.0 co-simulation functions over the FMU's Python slave (Linux).
 *
 * It takes the place of pythonfmu 0.7.0's binary behind the status shim (status_shim.c loads it
 * as ORIGINAL_LIBRARY and forwards every call to it) and keeps that binary's contract with the
 * slave, so that the same slave (a pythonfmu Fmi2Slave) runs behind either, and behind pythonfmu's
 * win64 binary:
 *   - fmi2Instantiate puts the resources folder at the front of sys.path (where it is not on it
 *     already), imports the model module
 *     and calls its model class with instance_name, resources and visible; fmi2Reset makes a new
 *     instance the same way;
 *   - every call is the slave's method of the same name (do_step, get_real, set_real, ...,
 *     _get_fmu_state, _set_fmu_state, _fmu_state_to_bytes, _fmu_state_from_bytes); do_step's
 *     False is fmi2Discard;
 *   - after every call the messages the slave queued (its _get_log_queue(), pythonfmu's LogMsg
 *     objects) go to the importer's logger, where fmi2SetDebugLogging lets them (the shim turns
 *     logging on and filters itself), those of fmi2Discard or worse always; '%' is doubled, the
 *     message being the logger's format;
 *   - a Python exception is fmi2Fatal, its repr logged (after the scene file's name, as every
 *     message of status fmi2Discard or worse).
 *
 * What it does not do that pythonfmu's binary did, and why this file exists (docs/performance.md,
 * FMU overhead):
 * at every fmi2Instantiate pythonfmu's binary read the model module's file again, compiled and
 * executed it a second time and tested each class it bound with regular expressions, and the
 * first instance of each load of the binary (an importer such as fmpy extracts the FMU into a new
 * folder at every run) started a thread and loaded a 284 KB C++ library. Here the module and the
 * class are named at build time (SLAVE_MODULE, SLAVE_CLASS), and the module is imported once per
 * process. The serialized bytes of a state are made once for fmi2SerializedFMUstateSize and
 * fmi2SerializeFMUstate (pythonfmu's binary made them twice).
 *
 * Python. The bridge does not link libpython: it runs in the importer's Python (fmpy, libcosimpy),
 * or, in a host without Python, in an interpreter it starts at the first fmi2Instantiate with
 * libpython preloaded (LD_PRELOAD), as pythonfmu's binary did; that interpreter runs until the
 * process exits (it is never finalised: modules such as numpy cannot be loaded twice). It is
 * compiled against Python's limited API (3.10), so one build runs under any Python from 3.10.
 *
 * Build (inerter/fmu/build.py does it):
 *   gcc -shared -fPIC -O2 -s -fvisibility=hidden -I<Python include> \
 *       -DSLAVE_MODULE='"<module>"' -DSLAVE_CLASS='"<model identifier>"' \
 *       -DSCENE_FILE='"<scene file>"' \
 *       -o <modelIdentifier>.bridge.so python_bridge.c -lpthread
 */
#define Py_LIMITED_API 0x030A0000
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <ctype.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2_types.h"
#include "log_format.h"

#if !defined(SLAVE_MODULE) || !defined(SLAVE_CLASS)
#error "compile with -DSLAVE_MODULE='\"<model module>\"' -DSLAVE_CLASS='\"<model class>\"'"
#endif
#ifndef SCENE_FILE
#error "compile with -DSCENE_FILE='\"<the scene file's name>\"' (the name its messages give)"
#endif

#define EXPORT __attribute__((visibility("default")))

/* An instance: the slave object and what its calls need. */
struct slave {
    PyObject *instance;  /* the model class's instance */
    PyObject *messages;  /* its log queue: a list the bridge empties after every call */
    PyObject *strings;   /* what the last fmi2GetString returned: its values point into it */
    PyObject *serialized;   /* the bytes of `serialized_of`, made for fmi2SerializedFMUstateSize */
    PyObject *serialized_of;
    char *name;          /* the instance name, copied */
    char *resources;     /* the resources folder, a path */
    int visible;
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment environment;
    int logging_on;
    size_t n_categories; /* those fmi2SetDebugLogging selected; none: all */
    char **categories;
};

/* ---------------------------------------------------------------------------------------------
 * The interpreter
 * ------------------------------------------------------------------------------------------- */
static pthread_once_t python_once = PTHREAD_ONCE_INIT;

/* Start Python where the host has not (its GIL released at once: every call takes it). */
static void start_python(void)
{
    if (!Py_IsInitialized()) {
        Py_InitializeEx(0); /* 0: the host's signal handlers stay its own */
        PyEval_SaveThread();
    }
}

/* ---------------------------------------------------------------------------------------------
 * Messages
 * ------------------------------------------------------------------------------------------- */
/* Whether a message of `status` and `category` reaches the importer: one of a status it must act
 * on (fmi2Discard or worse) always, the others where fmi2SetDebugLogging lets them through
 * (pythonfmu's rule: logging on, and the category selected or none named). */
static int selected(const struct slave *s, fmi2Status status, const char *category)
{
    size_t i;
    if (status >= fmi2Discard)
        return 1;
    if (!s->logging_on)
        return 0;
    if (s->n_categories == 0)
        return 1;
    for (i = 0; i < s->n_categories; i++)
        if (category != NULL && strcmp(category, s->categories[i]) == 0)
            return 1;
    return 0;
}

/* `message` to the importer's logger as its format (as_format: '%' doubled). */
static void say(const struct slave *s, fmi2Status status, const char *category,
                const char *message)
{
    char *text;

    if (s->logger == NULL || message == NULL || !selected(s, status, category))
        return;
    text = as_format(message);
    if (text == NULL)
        return;
    s->logger(s->environment, s->name, status, category, text);
    free(text);
}

/* A text attribute of a queued message, or NULL (None, not text). */
static const char *text_of(PyObject *message, const char *attribute, PyObject **owner)
{
    *owner = PyObject_GetAttrString(message, attribute);
    if (*owner == NULL || !PyUnicode_Check(*owner)) {
        PyErr_Clear();
        return NULL;
    }
    return PyUnicode_AsUTF8AndSize(*owner, NULL);
}

/* The slave's queued messages to the importer, the queue emptied. With the GIL. */
static void flush(struct slave *s)
{
    Py_ssize_t i, n;

    if (s->messages == NULL || !PyList_Check(s->messages))
        return;
    n = PyList_Size(s->messages);
    for (i = 0; i < n; i++) {
        PyObject *message = PyList_GetItem(s->messages, i); /* borrowed */
        PyObject *status_object = PyObject_GetAttrString(message, "status");
        long status = status_object != NULL ? PyLong_AsLong(status_object) : (long)fmi2Error;
        PyObject *category_owner, *text_owner;
        const char *category = text_of(message, "category", &category_owner);
        const char *text = text_of(message, "msg", &text_owner);

        if (PyErr_Occurred())
            PyErr_Clear();
        if (status < fmi2OK || status > fmi2Pending)
            status = fmi2Error;
        say(s, (fmi2Status)status, category != NULL ? category : "logAll",
            text != NULL ? text : "(a message that is not text)");
        Py_XDECREF(status_object);
        Py_XDECREF(category_owner);
        Py_XDECREF(text_owner);
    }
    PyList_SetSlice(s->messages, 0, n, NULL);
    PyErr_Clear();
}

/* A Python exception in `call`: logged with its repr; fmi2Fatal. With the GIL. */
static fmi2Status failed(struct slave *s, const char *call)
{
    PyObject *type, *value, *traceback, *repr = NULL;
    const char *text = NULL;
    char message[2048];

    PyErr_Fetch(&type, &value, &traceback);
    if (value != NULL)
        repr = PyObject_Repr(value);
    if (repr != NULL)
        text = PyUnicode_AsUTF8AndSize(repr, NULL);
    PyErr_Clear();
    snprintf(message, sizeof message, "%s: %s: the slave raised %s", SCENE_FILE, call,
             text != NULL ? text : "an exception");
    flush(s);
    say(s, fmi2Fatal, "logStatusFatal", message);
    Py_XDECREF(repr);
    Py_XDECREF(type);
    Py_XDECREF(value);
    Py_XDECREF(traceback);
    return fmi2Fatal;
}

/* The end of a call with the GIL: the result consumed, the messages flushed. */
static fmi2Status done(struct slave *s, PyObject *result, const char *call)
{
    if (result == NULL)
        return failed(s, call);
    Py_DECREF(result);
    flush(s);
    return fmi2OK;
}

/* ---------------------------------------------------------------------------------------------
 * Instantiation
 * ------------------------------------------------------------------------------------------- */
/* The value of the hex digit `c`. */
static int hex_value(char c)
{
    return c <= '9' ? c - '0' : (c | 0x20) - 'a' + 10;
}

/* The folder a file URI names (file:///a%20b/resources -> /a b/resources), or the text as is. */
static char *uri_path(const char *uri)
{
    const char *from = uri;
    char *path, *to;

    if (strncmp(from, "file://", 7) == 0) {
        from += 7;
        if (strncmp(from, "localhost/", 10) == 0)
            from += 9;
    } else if (strncmp(from, "file:/", 6) == 0) {
        from += 5;
    }
    path = malloc(strlen(from) + 1);
    if (path == NULL)
        return NULL;
    for (to = path; *from != '\0'; from++) {
        if (from[0] == '%' && isxdigit((unsigned char)from[1]) && isxdigit((unsigned char)from[2])) {
            *to++ = (char)(hex_value(from[1]) * 16 + hex_value(from[2]));
            from += 2;
        } else {
            *to++ = *from;                /* a '%' not followed by two hex digits stays as it is */
        }
    }
    *to = '\0';
    return path;
}

/* `folder` at the front of sys.path, unless it is there already. With the GIL. */
static int on_path(const char *folder)
{
    PyObject *path = PySys_GetObject("path"); /* borrowed */
    PyObject *entry = PyUnicode_DecodeFSDefault(folder);
    int found, result = -1;

    if (path == NULL || entry == NULL) {
        Py_XDECREF(entry);
        return -1;
    }
    found = PySequence_Contains(path, entry);
    if (found == 1)
        result = 0;
    else if (found == 0)
        result = PyList_Insert(path, 0, entry);
    Py_DECREF(entry);
    return result;
}

/* A new instance of the model class for `s` (replacing any), its log queue read. With the GIL. */
static fmi2Status make_instance(struct slave *s)
{
    PyObject *module, *model, *arguments, *folder, *keywords = NULL, *instance = NULL;

    if (on_path(s->resources) != 0)
        return failed(s, "fmi2Instantiate (sys.path)");
    module = PyImport_ImportModule(SLAVE_MODULE);
    if (module == NULL)
        return failed(s, "fmi2Instantiate (import " SLAVE_MODULE ")");
    model = PyObject_GetAttrString(module, SLAVE_CLASS);
    Py_DECREF(module);
    if (model == NULL)
        return failed(s, "fmi2Instantiate (" SLAVE_MODULE "." SLAVE_CLASS ")");
    arguments = PyTuple_New(0);
    folder = PyUnicode_DecodeFSDefault(s->resources);
    if (arguments != NULL && folder != NULL)
        keywords = Py_BuildValue("{s:s,s:O,s:O}", "instance_name", s->name, "resources", folder,
                                 "visible", s->visible ? Py_True : Py_False);
    Py_XDECREF(folder);
    if (keywords != NULL)
        instance = PyObject_Call(model, arguments, keywords);
    Py_DECREF(model);
    Py_XDECREF(arguments);
    Py_XDECREF(keywords);
    if (instance == NULL)
        return failed(s, "fmi2Instantiate (" SLAVE_CLASS "(...))");
    Py_XDECREF(s->instance);
    Py_XDECREF(s->messages);
    s->instance = instance;
    s->messages = PyObject_CallMethod(instance, "_get_log_queue", NULL);
    if (s->messages == NULL)
        return failed(s, "fmi2Instantiate (_get_log_queue)");
    flush(s);
    return fmi2OK;
}

static void free_slave(struct slave *s)
{
    size_t i;
    for (i = 0; i < s->n_categories; i++)
        free(s->categories[i]);
    free(s->categories);
    free(s->name);
    free(s->resources);
    free(s);
}

/* The serialized bytes made for `state` dropped (any state's where `state` is NULL): the state is
 * released, and its address may be another's next. With the GIL. */
static void forget_serialized(struct slave *s, fmi2FMUstate state)
{
    if (state == NULL || state == (fmi2FMUstate)s->serialized_of) {
        Py_CLEAR(s->serialized);
        s->serialized_of = NULL;
    }
}

/* The references `s` holds, released. With the GIL. */
static void release(struct slave *s)
{
    Py_CLEAR(s->instance);
    Py_CLEAR(s->messages);
    Py_CLEAR(s->strings);
    forget_serialized(s, NULL);
}

EXPORT const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
EXPORT const char *fmi2GetVersion(void) { return fmi2Version; }

EXPORT fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType,
                                     fmi2String fmuGUID, fmi2String fmuResourceLocation,
                                     const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                                     fmi2Boolean loggingOn)
{
    struct slave *s = calloc(1, sizeof *s);
    PyGILState_STATE gil;
    fmi2Status status;

    (void)fmuGUID;
    if (s == NULL)
        return NULL;
    s->name = strdup(instanceName != NULL ? instanceName : "");
    s->resources = uri_path(fmuResourceLocation != NULL ? fmuResourceLocation : "");
    s->visible = visible == fmi2True;
    s->logging_on = loggingOn == fmi2True;
    if (functions != NULL) {
        s->logger = functions->logger;
        s->environment = functions->componentEnvironment;
    }
    if (s->name == NULL || s->resources == NULL) {
        free_slave(s);
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        say(s, fmi2Error, "logStatusError", SCENE_FILE ": fmi2Instantiate: this FMU is for "
            "co-simulation only (fmuType fmi2CoSimulation); no instance is made");
        free_slave(s);
        return NULL;
    }
    pthread_once(&python_once, start_python);
    gil = PyGILState_Ensure();
    status = make_instance(s);
    if (status != fmi2OK)
        release(s);
    PyGILState_Release(gil);
    if (status != fmi2OK) {
        free_slave(s);
        return NULL;
    }
    return s;
}

EXPORT void fmi2FreeInstance(fmi2Component c)
{
    PyGILState_STATE gil;
    if (c == NULL)
        return;
    gil = PyGILState_Ensure();
    release(c);
    PyGILState_Release(gil);
    free_slave(c);
}

EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                                      const fmi2String categories[])
{
    struct slave *s = c;
    char **copied = NULL;
    size_t i, n = 0;

    if (s == NULL)
        return fmi2Error;
    if (nCategories > 0 && categories != NULL) {
        copied = calloc(nCategories, sizeof *copied);
        if (copied == NULL)
            return fmi2Error;
        for (i = 0; i < nCategories; i++)
            if (categories[i] != NULL && (copied[n] = strdup(categories[i])) != NULL)
                n++;
    }
    for (i = 0; i < s->n_categories; i++)
        free(s->categories[i]);
    free(s->categories);
    s->categories = copied;
    s->n_categories = n;
    s->logging_on = loggingOn == fmi2True;
    return fmi2OK;
}

/* ---------------------------------------------------------------------------------------------
 * Calls of the slave's methods
 * ------------------------------------------------------------------------------------------- */
/* `expression` (a new reference or NULL) with the GIL held, ended by `done`. */
#define CALL(c, call, expression)                                                                \
    {                                                                                            \
        struct slave *s_ = (c);                                                                  \
        PyGILState_STATE gil_;                                                                   \
        fmi2Status status_;                                                                      \
        if (s_ == NULL || s_->instance == NULL)                                                  \
            return fmi2Error;                                                                    \
        gil_ = PyGILState_Ensure();                                                              \
        status_ = done(s_, (expression), call);                                                  \
        PyGILState_Release(gil_);                                                                \
        return status_;                                                                          \
    }
#define METHOD(c, name, ...) PyObject_CallMethod(((struct slave *)(c))->instance, name, __VA_ARGS__)

/* The slave's setup_experiment(start, stop or None, tolerance or None). With the GIL. */
static PyObject *setup_experiment(struct slave *s, fmi2Boolean toleranceDefined,
                                  fmi2Real tolerance, fmi2Real startTime,
                                  fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    PyObject *stop, *rtol, *result = NULL;

    stop = stopTimeDefined == fmi2True ? PyFloat_FromDouble(stopTime) : Py_NewRef(Py_None);
    rtol = toleranceDefined == fmi2True ? PyFloat_FromDouble(tolerance) : Py_NewRef(Py_None);
    if (stop != NULL && rtol != NULL)
        result = PyObject_CallMethod(s->instance, "setup_experiment", "dOO", startTime, stop, rtol);
    Py_XDECREF(stop);
    Py_XDECREF(rtol);
    return result;
}

EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                                      fmi2Real tolerance, fmi2Real startTime,
                                      fmi2Boolean stopTimeDefined, fmi2Real stopTime)
    CALL(c, "fmi2SetupExperiment", setup_experiment(c, toleranceDefined, tolerance, startTime,
                                                    stopTimeDefined, stopTime))

EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component c)
    CALL(c, "fmi2EnterInitializationMode", METHOD(c, "enter_initialization_mode", NULL))

EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c)
    CALL(c, "fmi2ExitInitializationMode", METHOD(c, "exit_initialization_mode", NULL))

EXPORT fmi2Status fmi2Terminate(fmi2Component c)
    CALL(c, "fmi2Terminate", METHOD(c, "terminate", NULL))

EXPORT fmi2Status fmi2Reset(fmi2Component c)
{
    struct slave *s = c;
    PyGILState_STATE gil;
    fmi2Status status;

    if (s == NULL || s->instance == NULL)
        return fmi2Error;
    gil = PyGILState_Ensure();
    Py_CLEAR(s->strings);
    forget_serialized(s, NULL);
    status = make_instance(s);
    PyGILState_Release(gil);
    return status;
}

EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                             fmi2Real communicationStepSize,
                             fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    struct slave *s = c;
    PyGILState_STATE gil;
    PyObject *result;
    fmi2Status status;
    int took;

    (void)noSetFMUStatePriorToCurrentPoint;
    if (s == NULL || s->instance == NULL)
        return fmi2Error;
    gil = PyGILState_Ensure();
    result = PyObject_CallMethod(s->instance, "do_step", "dd", currentCommunicationPoint,
                                 communicationStepSize);
    took = result != NULL ? PyObject_IsTrue(result) : -1;
    if (took < 0) {
        Py_XDECREF(result);
        status = failed(s, "fmi2DoStep");
    } else {
        status = done(s, result, "fmi2DoStep");
        if (status == fmi2OK && !took)
            status = fmi2Discard;
    }
    PyGILState_Release(gil);
    return status;
}

/* ---------------------------------------------------------------------------------------------
 * Variables
 * ------------------------------------------------------------------------------------------- */
/* vr[0..nvr) as a list of ints, or NULL. With the GIL. */
static PyObject *references(const fmi2ValueReference vr[], size_t nvr)
{
    PyObject *list = PyList_New((Py_ssize_t)nvr);
    size_t i;
    for (i = 0; list != NULL && i < nvr; i++) {
        PyObject *item = PyLong_FromUnsignedLong(vr[i]);
        if (item == NULL || PyList_SetItem(list, (Py_ssize_t)i, item) != 0)
            Py_CLEAR(list);
    }
    return list;
}

/* Whether a getter or setter may enter the slave: an instance, and arrays where nvr > 0. */
static int callable(const struct slave *s, size_t nvr, const void *vr, const void *values)
{
    return s != NULL && s->instance != NULL && (nvr == 0 || (vr != NULL && values != NULL));
}

/* The getter `method`'s values for vr[0..nvr), each passed to `store` (0: taken, else an
 * exception is set). With `keep`, the result must be a list, and is kept in slave.strings until
 * the next such call: the values point into it. */
typedef int store_fn(PyObject *item, void *values, size_t i);

static fmi2Status get(fmi2Component c, const char *method, const char *call,
                      const fmi2ValueReference vr[], size_t nvr, void *values, store_fn *store,
                      int keep)
{
    struct slave *s = c;
    PyGILState_STATE gil;
    PyObject *list, *result = NULL;
    fmi2Status status;
    size_t i;

    if (!callable(s, nvr, vr, values))
        return fmi2Error;
    gil = PyGILState_Ensure();
    list = references(vr, nvr);
    if (list != NULL)
        result = PyObject_CallMethod(s->instance, method, "O", list);
    Py_XDECREF(list);
    if (result != NULL && ((keep && !PyList_Check(result)) ||
                           PySequence_Size(result) != (Py_ssize_t)nvr)) {
        if (!PyErr_Occurred())
            PyErr_Format(PyExc_ValueError, "%s did not return a %s of %zu values", method,
                         keep ? "list" : "sequence", nvr);
        Py_CLEAR(result);
    }
    for (i = 0; result != NULL && i < nvr; i++) {
        PyObject *item = PySequence_GetItem(result, (Py_ssize_t)i);
        if (item == NULL || store(item, values, i) != 0)
            Py_CLEAR(result);
        Py_XDECREF(item);
    }
    if (result != NULL && keep) {
        PyObject *previous = s->strings;
        s->strings = Py_NewRef(result);
        Py_XDECREF(previous);
    }
    status = done(s, result, call);
    PyGILState_Release(gil);
    return status;
}

static int store_real(PyObject *item, void *values, size_t i)
{
    ((fmi2Real *)values)[i] = PyFloat_AsDouble(item);
    return PyErr_Occurred() != NULL;
}

static int store_integer(PyObject *item, void *values, size_t i)
{
    ((fmi2Integer *)values)[i] = (fmi2Integer)PyLong_AsLong(item);
    return PyErr_Occurred() != NULL;
}

static int store_boolean(PyObject *item, void *values, size_t i)
{
    int truth = PyObject_IsTrue(item);
    ((fmi2Boolean *)values)[i] = truth > 0 ? fmi2True : fmi2False;
    return truth < 0;
}

/* A String's value points into the text object, which the result list keeps (slave.strings)
 * until the next fmi2GetString (the list holds the item beyond its reference here). */
static int store_string(PyObject *item, void *values, size_t i)
{
    const char *text = PyUnicode_Check(item) ? PyUnicode_AsUTF8AndSize(item, NULL) : NULL;
    if (text == NULL && !PyErr_Occurred())
        PyErr_SetString(PyExc_TypeError, "get_string returned a value that is not text");
    ((fmi2String *)values)[i] = text;
    return text == NULL;
}

/* fmi2GetReal, fmi2GetInteger, fmi2GetBoolean, fmi2GetString: the slave's get_<type>. */
#define GETTER(Type, type, keep)                                                                 \
    EXPORT fmi2Status fmi2Get##Type(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,  \
                                    fmi2##Type value[])                                          \
    {                                                                                            \
        return get(c, "get_" #type, "fmi2Get" #Type, vr, nvr, value, store_##type, keep);        \
    }
GETTER(Real, real, 0)
GETTER(Integer, integer, 0)
GETTER(Boolean, boolean, 0)
GETTER(String, string, 1)
#undef GETTER

/* The setter `method` with vr[0..nvr) and their values, each made by `make`. */
typedef PyObject *make_fn(const void *values, size_t i);

static fmi2Status set(fmi2Component c, const char *method, const char *call,
                      const fmi2ValueReference vr[], size_t nvr, const void *values,
                      make_fn *make)
{
    struct slave *s = c;
    PyGILState_STATE gil;
    PyObject *list, *items, *result = NULL;
    fmi2Status status;
    size_t i;

    if (!callable(s, nvr, vr, values))
        return fmi2Error;
    gil = PyGILState_Ensure();
    list = references(vr, nvr);
    items = PyList_New((Py_ssize_t)nvr);
    for (i = 0; items != NULL && i < nvr; i++) {
        PyObject *item = make(values, i);
        if (item == NULL || PyList_SetItem(items, (Py_ssize_t)i, item) != 0)
            Py_CLEAR(items);
    }
    if (list != NULL && items != NULL)
        result = PyObject_CallMethod(s->instance, method, "OO", list, items);
    Py_XDECREF(list);
    Py_XDECREF(items);
    status = done(s, result, call);
    PyGILState_Release(gil);
    return status;
}

static PyObject *make_real(const void *values, size_t i)
{
    return PyFloat_FromDouble(((const fmi2Real *)values)[i]);
}

static PyObject *make_integer(const void *values, size_t i)
{
    return PyLong_FromLong(((const fmi2Integer *)values)[i]);
}

static PyObject *make_boolean(const void *values, size_t i)
{
    return PyBool_FromLong(((const fmi2Boolean *)values)[i] != fmi2False);
}

/* A String's value as text: its bytes as UTF-8, any that are not replaced (U+FFFD); NULL as "". */
static PyObject *make_string(const void *values, size_t i)
{
    const char *text = ((const fmi2String *)values)[i];
    if (text == NULL)
        text = "";
    return PyUnicode_DecodeUTF8(text, (Py_ssize_t)strlen(text), "replace");
}

/* fmi2SetReal, fmi2SetInteger, fmi2SetBoolean, fmi2SetString: the slave's set_<type>. */
#define SETTER(Type, type)                                                                       \
    EXPORT fmi2Status fmi2Set##Type(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,  \
                                    const fmi2##Type value[])                                    \
    {                                                                                            \
        return set(c, "set_" #type, "fmi2Set" #Type, vr, nvr, value, make_##type);               \
    }
SETTER(Real, real)
SETTER(Integer, integer)
SETTER(Boolean, boolean)
SETTER(String, string)
#undef SETTER

/* ---------------------------------------------------------------------------------------------
 * FMU state: the slave's state object, held by reference
 * ------------------------------------------------------------------------------------------- */
EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    struct slave *s = c;
    PyGILState_STATE gil;
    PyObject *state;
    fmi2Status status;

    if (s == NULL || s->instance == NULL || FMUstate == NULL)
        return fmi2Error;
    gil = PyGILState_Ensure();
    state = PyObject_CallMethod(s->instance, "_get_fmu_state", NULL);
    if (state == NULL) {
        status = failed(s, "fmi2GetFMUstate");
    } else {
        /* FMI 2.0: a state given back is one this FMU made and may reuse; replaced here */
        if (*FMUstate != NULL)
            forget_serialized(s, *FMUstate);
        Py_XDECREF((PyObject *)*FMUstate);
        *FMUstate = state;
        flush(s);
        status = fmi2OK;
    }
    PyGILState_Release(gil);
    return status;
}

EXPORT fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    if (FMUstate == NULL)
        return fmi2Error;
    CALL(c, "fmi2SetFMUstate", METHOD(c, "_set_fmu_state", "O", (PyObject *)FMUstate))
}

EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    struct slave *s = c;
    PyGILState_STATE gil;

    if (s == NULL || FMUstate == NULL)
        return fmi2Error;
    if (*FMUstate == NULL)
        return fmi2OK;
    gil = PyGILState_Ensure();
    forget_serialized(s, *FMUstate);
    Py_DECREF((PyObject *)*FMUstate);
    *FMUstate = NULL;
    PyGILState_Release(gil);
    return fmi2OK;
}

/* The bytes of `state`, made once for the size and the copy. With the GIL; NULL: an exception. */
static PyObject *serialized(struct slave *s, fmi2FMUstate state)
{
    PyObject *bytes;
    if (s->serialized != NULL && s->serialized_of == (PyObject *)state)
        return s->serialized;
    bytes = PyObject_CallMethod(s->instance, "_fmu_state_to_bytes", "O", (PyObject *)state);
    if (bytes != NULL && !PyBytes_Check(bytes)) {
        PyErr_SetString(PyExc_TypeError, "_fmu_state_to_bytes did not return bytes");
        Py_CLEAR(bytes);
    }
    if (bytes == NULL)
        return NULL;
    Py_XDECREF(s->serialized);
    s->serialized = bytes;
    s->serialized_of = (PyObject *)state;
    return bytes;
}

/* The size of `state`'s bytes into *size, or (size NULL) the bytes into `into`, which holds
 * `room` bytes. */
static fmi2Status serialize(fmi2Component c, fmi2FMUstate state, const char *call, size_t *size,
                            fmi2Byte *into, size_t room)
{
    struct slave *s = c;
    PyGILState_STATE gil;
    PyObject *bytes;
    fmi2Status status = fmi2OK;

    if (s == NULL || s->instance == NULL || state == NULL || (size == NULL && into == NULL))
        return fmi2Error;
    gil = PyGILState_Ensure();
    bytes = serialized(s, state);
    if (bytes == NULL) {
        status = failed(s, call);
    } else if (size != NULL) {
        *size = (size_t)PyBytes_Size(bytes);
    } else if ((size_t)PyBytes_Size(bytes) > room) {
        say(s, fmi2Error, "logStatusError", SCENE_FILE ": fmi2SerializeFMUstate: the buffer is "
            "shorter than fmi2SerializedFMUstateSize gave; nothing is written");
        status = fmi2Error;
    } else {
        memcpy(into, PyBytes_AsString(bytes), (size_t)PyBytes_Size(bytes));
    }
    flush(s);
    PyGILState_Release(gil);
    return status;
}

EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    if (size == NULL)
        return fmi2Error;
    return serialize(c, FMUstate, "fmi2SerializedFMUstateSize", size, NULL, 0);
}

EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate,
                                        fmi2Byte serializedState[], size_t size)
{
    if (serializedState == NULL)
        return fmi2Error;
    return serialize(c, FMUstate, "fmi2SerializeFMUstate", NULL, serializedState, size);
}

EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[],
                                          size_t size, fmi2FMUstate *FMUstate)
{
    struct slave *s = c;
    PyGILState_STATE gil;
    PyObject *bytes, *state = NULL;
    fmi2Status status;

    if (s == NULL || s->instance == NULL || FMUstate == NULL ||
        (serializedState == NULL && size > 0))
        return fmi2Error;
    gil = PyGILState_Ensure();
    bytes = PyBytes_FromStringAndSize(serializedState, (Py_ssize_t)size);
    if (bytes != NULL)
        state = PyObject_CallMethod(s->instance, "_fmu_state_from_bytes", "O", bytes);
    Py_XDECREF(bytes);
    if (state == NULL) {
        status = failed(s, "fmi2DeSerializeFMUstate");
    } else {
        *FMUstate = state;
        flush(s);
        status = fmi2OK;
    }
    PyGILState_Release(gil);
    return status;
}

/* ---------------------------------------------------------------------------------------------
 * What the FMU does not support (the shim answers these itself; here for a complete API)
 * ------------------------------------------------------------------------------------------- */
EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[],
                                               size_t nu, const fmi2ValueReference k[], size_t nk,
                                               const fmi2Real dk[], fmi2Real du[])
{
    (void)c, (void)u, (void)nu, (void)k, (void)nk, (void)dk, (void)du;
    return fmi2Error;
}

EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                              size_t nvr, const fmi2Integer order[],
                                              const fmi2Real value[])
{
    (void)c, (void)vr, (void)nvr, (void)order, (void)value;
    return fmi2Error;
}

EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                               size_t nvr, const fmi2Integer order[],
                                               fmi2Real value[])
{
    (void)c, (void)vr, (void)nvr, (void)order, (void)value;
    return fmi2Error;
}

EXPORT fmi2Status fmi2CancelStep(fmi2Component c)
{
    (void)c;
    return fmi2Error;
}

/* The status functions: the shim answers them from the slave's variables; here fmi2Discard
 * (FMI 2.0 section 2.1.3: the status cannot be given). */
EXPORT fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)c, (void)s, (void)value;
    return fmi2Discard;
}

EXPORT fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    (void)c, (void)s, (void)value;
    return fmi2Discard;
}

EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s,
                                       fmi2Integer *value)
{
    (void)c, (void)s, (void)value;
    return fmi2Discard;
}

EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s,
                                       fmi2Boolean *value)
{
    (void)c, (void)s, (void)value;
    return fmi2Discard;
}

EXPORT fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)c, (void)s, (void)value;
    return fmi2Discard;
}
