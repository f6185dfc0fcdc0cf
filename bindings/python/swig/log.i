// SPDX-License-Identifier: Apache-2.0
/*
 * flatline/log.h: the library's log, routed to Python's logging.
 *
 * The C callback runs on whichever thread logs (a gauge worker, an
 * acquisition thread), often while the thread that holds the GIL waits in
 * the library: it must never take the GIL. So it only copies the message
 * into a ring here (a PyThread lock, usable without the GIL), and
 * flatline._log takes the messages out with the GIL and hands them to
 * logging.getLogger("flatline"): after the gauge's waiting calls and from
 * a daemon thread every 0.2 s.
 */
%{
#include "flatline/log.h"

#define FLT_PY_LOG_RING 256
typedef struct flt_py_log_record {
    int level;
    char component[32];
    char message[512];
} flt_py_log_record;
static flt_py_log_record flt_py_log_ring[FLT_PY_LOG_RING];
static size_t flt_py_log_head = 0, flt_py_log_count = 0, flt_py_log_lost = 0;
static PyThread_type_lock flt_py_log_lock = NULL;

static void FLT_CALL flt_py_log_callback(flt_log_level level, const char *component,
                                         const char *message, void *user) {
    flt_py_log_record *r;
    (void)user;
    PyThread_acquire_lock(flt_py_log_lock, WAIT_LOCK);
    if (flt_py_log_count == FLT_PY_LOG_RING) {
        ++flt_py_log_lost;
    } else {
        r = &flt_py_log_ring[(flt_py_log_head + flt_py_log_count) % FLT_PY_LOG_RING];
        r->level = (int)level;
        PyOS_snprintf(r->component, sizeof r->component, "%s", component);
        PyOS_snprintf(r->message, sizeof r->message, "%s", message);
        ++flt_py_log_count;
    }
    PyThread_release_lock(flt_py_log_lock);
}
%}

%inline %{
/* Routes the library's log to this module's ring (every level). */
flt_status flt_py_log_install(void) {
    if (flt_py_log_lock == NULL) {
        flt_py_log_lock = PyThread_allocate_lock();
        if (flt_py_log_lock == NULL) {
            flt_set_last_error(FLT_ERR_OUT_OF_MEMORY, "flt_py_log_install: no lock");
            return FLT_ERR_OUT_OF_MEMORY;
        }
    }
    return flt_log_set_callback(flt_py_log_callback, NULL, FLT_LOG_DEBUG);
}

/* The messages waiting, oldest first, as ((level, component, message),
 * ...), and how many were lost to a full ring since the last call. */
PyObject *flt_py_log_take(void) {
    PyObject *records, *item;
    size_t i, n, lost;
    if (flt_py_log_lock == NULL)
        return Py_BuildValue("(()n)", (Py_ssize_t)0);
    PyThread_acquire_lock(flt_py_log_lock, WAIT_LOCK);
    n = flt_py_log_count;
    lost = flt_py_log_lost;
    records = PyTuple_New((Py_ssize_t)n);
    for (i = 0; records != NULL && i < n; ++i) {
        const flt_py_log_record *r = &flt_py_log_ring[(flt_py_log_head + i) % FLT_PY_LOG_RING];
        item = Py_BuildValue("(iss)", r->level, r->component, r->message);
        if (item == NULL) {
            Py_CLEAR(records);
            break;
        }
        PyTuple_SET_ITEM(records, (Py_ssize_t)i, item);
    }
    if (records != NULL) {
        flt_py_log_head = (flt_py_log_head + n) % FLT_PY_LOG_RING;
        flt_py_log_count = 0;
        flt_py_log_lost = 0;
    }
    PyThread_release_lock(flt_py_log_lock);
    if (records == NULL)
        return NULL;
    return Py_BuildValue("(Nn)", records, (Py_ssize_t)lost);
}
%}

%ignore flt_log_set_callback;
%include "flatline/log.h"
