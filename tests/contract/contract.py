# SPDX-License-Identifier: Apache-2.0
"""The promises every call of libflatline keeps (README.md in this folder),
as checks the property tests apply to each call they make, and strategies
that draw options and values anywhere inside the documented ranges,
boundaries included."""

from __future__ import annotations

import ctypes
import functools
import math
import re
import time
from typing import Any, Callable, Dict, List, Optional, Tuple

import numpy as np
from hypothesis import strategies as st

import flatline
from flatline import capi

# -- the promises ---------------------------------------------------------------

#: Seconds a call may take, fixed part and per row it handles. Far above
#: what the library needs (microseconds per row): they catch a call that
#: runs away (seconds per row, as fine knots across a kilometre once did),
#: with room for a machine loaded twenty-fold.
FIXED_SECONDS = 3.0
SECONDS_PER_ROW = 0.05
#: Seconds per MB a create call writes: the components write every buffer
#: at create (docs/memory.md), about 400 MB/s on the development machine,
#: so 20 MB/s leaves room for a machine loaded twenty-fold.
SECONDS_PER_MB = 0.05

#: A NaN in a reconstructed height is allowed only with one of these flags.
NAN_FLAGS = flatline.FLAG_NO_DATA | getattr(flatline, "FLAG_OFF_STRIP", 0)

_NAMED = re.compile(r"^\s*[A-Za-z_][\w.]*(\(\))?[:\s]")


class Tally:
    """Counts of what the suite saw, printed at the end (README.md)."""

    calls = 0
    refused: Dict[str, int] = {}

    @classmethod
    def refusal(cls, error: BaseException) -> None:
        name = type(error).__name__
        cls.refused[name] = cls.refused.get(name, 0) + 1


def check_refusal(what: str, error: BaseException) -> None:
    """A refusal carries a status (for the library's errors) and a message
    that names the function or argument; FLT_ERR_INTERNAL is a bug."""
    assert not isinstance(error, flatline.InternalError), f"{what}: internal error: {error}"
    message = str(error)
    assert message.strip(), f"{what}: {type(error).__name__} without a message"
    if isinstance(error, flatline.FlatlineError):
        assert isinstance(error.status, int) and error.status < 0, \
            f"{what}: {type(error).__name__} with status {error.status!r}"
    assert _NAMED.match(message), f"{what}: the message names nothing: {message!r}"


#: The library objects (Flatness, Reconstructor, Extractor, ...) that calls
#: made and that are not closed yet; `closing` closes them at the end of
#: every example.
_OPENED: List[Any] = []


def _heap_trimmer() -> Callable[[], Any]:
    """glibc's malloc_trim, or nothing where the C library has none."""
    try:
        trim = ctypes.CDLL(None).malloc_trim
    except (AttributeError, OSError):
        return lambda: None
    trim.argtypes = [ctypes.c_size_t]
    return lambda: trim(0)


# After each example (closing; the state machines' teardown) the C heap gives what was freed back to the system:
# glibc keeps freed blocks below its mmap threshold (which rises to 32 MB as
# large blocks are freed) in its arenas, so without it the resident set grew
# with the number of mid-sized examples drawn (a third more at scale 3), and
# what the suite's peak measures would not be what is still live.
trim_heap = _heap_trimmer()


def closing(test: Callable[..., Any]) -> Callable[..., Any]:
    """Closes every library object the example created through `call`,
    however the example ends. Put it under @given, so that it wraps each
    example. Hypothesis keeps the exception of every failing example it
    meets while shrinking, and with it the example's frames and their
    locals: an object left open there kept its C buffers (hundreds of MB
    for a large flat_row_capacity) until the end of the run. close()
    frees them at once, whatever still refers to the object."""

    @functools.wraps(test)
    def run(*args: Any, **kwargs: Any) -> Any:
        mark = len(_OPENED)
        try:
            return test(*args, **kwargs)
        finally:
            while len(_OPENED) > mark:
                _OPENED.pop().close()
            trim_heap()

    return run


def call(what: str, fn: Callable[..., Any], *args: Any, rows: int = 1,
         megabytes: float = 0.0, **kwargs: Any) -> Tuple[bool, Any]:
    """Calls fn: (True, result), or (False, the exception) when the library
    or the binding refused with a FlatlineError, ValueError or TypeError
    (each checked by check_refusal). Anything else (OverflowError,
    SystemError, IndexError, ...) breaks the contract and propagates; so
    does a call slower than FIXED_SECONDS + SECONDS_PER_ROW * rows +
    SECONDS_PER_MB * megabytes (what a create call allocates)."""
    start = time.perf_counter()
    try:
        result = fn(*args, **kwargs)
        ok = True
        if callable(getattr(result, "close", None)) and \
                type(result).__module__.startswith("flatline"):
            _OPENED.append(result)
    except (flatline.FlatlineError, ValueError, TypeError) as error:
        check_refusal(what, error)
        Tally.refusal(error)
        result, ok = error, False
    elapsed = time.perf_counter() - start
    Tally.calls += 1
    limit = FIXED_SECONDS + SECONDS_PER_ROW * max(1, rows) + SECONDS_PER_MB * megabytes
    assert elapsed <= limit, f"{what}: {elapsed:.2f} s for {rows} rows (limit {limit:.2f} s)"
    return ok, result


def assert_nan_flagged(what: str, z: np.ndarray, flags: np.ndarray, mask: int) -> None:
    """Every NaN in z has a flag of `mask` in flags; every other value is
    finite."""
    z = np.asarray(z)
    bad = ~np.isfinite(z) & ((np.asarray(flags) & mask) == 0)
    if bad.any():
        where = tuple(int(i[0]) for i in np.nonzero(bad))
        raise AssertionError(f"{what}: {int(bad.sum())} values non-finite without a flag, "
                             f"first at {where}: {z[where]!r} flags {np.asarray(flags)[where]}")


# -- options ------------------------------------------------------------------------

OPTIONS = flatline.options()


def _log_uniform(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda e: min(hi, max(lo, 10.0 ** e)))


def option_value(name: str) -> st.SearchStrategy[float]:
    """A value of option `name` inside its documented range: the ends, the
    default, and values spread over the range (log-uniform over decades)."""
    info = OPTIONS[name]
    lo, hi = info.min_value, info.max_value
    ends = [st.just(lo), st.just(info.default)]
    if math.isfinite(hi):
        ends.append(st.just(hi))
    if info.is_integer:
        top = int(hi) if math.isfinite(hi) else 2**31
        inner = st.integers(int(lo), top)
        if lo >= 1 and top / max(lo, 1) > 1000:
            inner = st.one_of(inner, _log_uniform(max(lo, 1), top).map(round))
        return st.one_of(*ends, inner).map(float)
    top = hi if math.isfinite(hi) else 1e300
    inner = [st.floats(lo, top, allow_nan=False, allow_infinity=False)]
    if lo > 0 and top / lo > 1000:
        inner.append(_log_uniform(lo, top))
    elif lo == 0 and top > 1000:
        inner.append(_log_uniform(1e-12, top))
    return st.one_of(*ends, *inner)


def options_of(prefixes: Tuple[str, ...], names=None) -> st.SearchStrategy[Dict[str, float]]:
    """Some of the options starting with `prefixes` (or of `names`), each at
    a value inside its range."""
    keys = sorted(n for n in OPTIONS if n.startswith(prefixes)) if names is None else names
    return st.fixed_dictionaries({}, optional={n: option_value(n) for n in keys})


def out_of_range(name: str) -> st.SearchStrategy[float]:
    """A value option `name` must refuse."""
    info = OPTIONS[name]
    bad = [st.just(math.nan), st.just(info.min_value - max(1.0, abs(info.min_value)))]
    if math.isfinite(info.max_value):
        bad.append(st.just(info.max_value * 2 + 1))
        bad.append(st.just(math.inf))
    bad.append(st.just(-math.inf))
    if info.is_integer:
        bad.append(st.just(info.min_value + 0.5))
    return st.one_of(*bad)


# -- values --------------------------------------------------------------------------

#: Scalars a careless or hostile caller passes: ordinary, the edges of what
#: the library calls a sample (1e9), just beyond, huge, tiny, non-finite.
SPECIAL = [0.0, -0.0, 1e9, -1e9, 1.0000001e9, 1e300, -1e300, 5e-324, math.nan,
           math.inf, -math.inf]


def block(rng: np.random.Generator, kind: int, rows: int, fibers: int,
          scale: float) -> np.ndarray:
    """A (rows, fibers) block of one of several kinds of content."""
    if kind == 0:  # a smooth sheet: a sine along travel, offsets across
        s = np.arange(rows)[:, None] * 3.0
        return scale * np.sin(s / 300.0 + np.arange(fibers)[None, :])
    if kind == 1:  # noise
        return rng.normal(0.0, scale, (rows, fibers))
    if kind == 2:  # constant
        return np.full((rows, fibers), scale)
    # sprinkled with special values
    out = rng.normal(0.0, scale, (rows, fibers))
    picks = rng.random((rows, fibers)) < 0.1
    out[picks] = rng.choice(SPECIAL, size=int(picks.sum()))
    return out


SCALES = st.sampled_from([0.0, 1e-12, 1e-3, 1.0, 12.0, 1e3, 1e8, 1e9, 2e9])


def positions(rng: np.random.Generator, start: float, rows: int, kind: int,
              max_jump: float) -> np.ndarray:
    """Strictly increasing row positions after `start` (mm) of one kind:
    the reference's 3 mm, jittered, sparse, the largest allowed jump."""
    if kind == 0:
        steps = np.full(rows, 3.0)
    elif kind == 1:
        steps = rng.uniform(0.5, 6.0, rows)
    elif kind == 2:
        steps = 10.0 ** rng.uniform(-3, math.log10(max(max_jump, 1.0)), rows)
    else:
        steps = np.full(rows, max_jump)
    return start + np.cumsum(np.minimum(steps, max_jump))
