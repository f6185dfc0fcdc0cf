# SPDX-License-Identifier: Apache-2.0
"""The library's log (flatline/log.h) in Python's logging, as the logger
``flatline``: frames dropped, rows lost, incomplete sheets, cuts ignored,
saturated laser peaks, a strip's head and end, camera faults...

The C library logs from its own threads; its messages wait in a small
queue in the extension (it never takes the GIL) and reach the logger from
a daemon thread every 0.2 s, and at once when a gauge call that waits
returns (flush, stop, run, next_sheet). Configure the logger as any other:

    logging.getLogger("flatline").setLevel(logging.WARNING)
"""

from __future__ import annotations

import logging
import threading

from . import capi as _capi

__all__ = ["logger", "drain", "install"]

#: The logger the library's messages go to.
logger = logging.getLogger("flatline")
_lock = threading.Lock()


def drain() -> None:
    """Hands every message waiting to the logger, oldest first."""
    with _lock:
        records, lost = _capi.flt_py_log_take()
        for level, component, message in records:
            if logger.isEnabledFor(level):
                logger.log(level, "%s: %s", component, message)
        if lost:
            logger.warning("log: %d messages lost (the binding's queue of 256 was full)", lost)


def _pump() -> None:
    stop = threading.Event()
    while not stop.wait(0.2):
        try:
            drain()
        except Exception:  # interpreter shutdown: nothing left to tell
            return


def install() -> None:
    """(Re)installs the library's log callback; done at import. Each
    installation starts the library's rate limits afresh (at most 5
    messages per place in 10 s, log.h)."""
    _capi.flt_py_log_install()


install()
threading.Thread(target=_pump, name="flatline log", daemon=True).start()
