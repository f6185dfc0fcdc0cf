# SPDX-License-Identifier: Apache-2.0
"""Keyword options: the C option names (flatline/common.h), mapped generically.

Nothing here lists the options: the table comes from the library itself
(flt_option_at / flt_option_info), so an option added to the C library is a
keyword argument in Python as soon as the library is rebuilt.
"""

from __future__ import annotations

import math
import numbers
from typing import Any, Dict, Mapping, NamedTuple, Optional, Tuple

from . import capi as _capi
from ._errors import NotFoundError


class OptionInfo(NamedTuple):
    """One option key as the library describes it."""

    name: str  #: the keyword, e.g. "knot_spacing"
    key: int  #: the C key (FLT_OPT_*)
    min_value: float  #: inclusive lower bound
    max_value: float  #: inclusive upper bound
    default: float  #: the C default
    is_integer: bool  #: True if only whole numbers are accepted


def option_info(name: str) -> OptionInfo:
    """Describes the option ``name``; raises NotFoundError (a KeyError) if the
    library has no option of that name."""
    if not isinstance(name, str):
        raise TypeError(f"option name must be a str, not {type(name).__name__}")
    key = _capi.flt_option_find(name)
    found_name, lo, hi, default, is_int = _capi.flt_option_info(key)
    return OptionInfo(found_name, int(key), lo, hi, default, bool(is_int))


def options() -> Dict[str, OptionInfo]:
    """Every option of the library, by name, in key order."""
    table: Dict[str, OptionInfo] = {}
    index = 0
    while True:
        try:
            key = _capi.flt_option_at(index)
        except NotFoundError:  # past the last key
            break
        name, lo, hi, default, is_int = _capi.flt_option_info(key)
        table[name] = OptionInfo(name, int(key), lo, hi, default, bool(is_int))
        index += 1
    return table


def _option_value(function: str, name: str, value: Any) -> float:
    """A keyword value as the double the C bag stores."""
    # bool is an int, but True as a length is a mistake worth reporting.
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(
            f"{function}() option '{name}' must be a real number, "
            f"not {type(value).__name__}"
        )
    return float(value)


def make_options(function: str, kwargs: Mapping[str, Any],
                 prefixes: Optional[Tuple[str, ...]] = None
                 ) -> Optional[_capi.flt_options]:
    """A C option bag holding `kwargs` (None when there are none, which the
    library reads as "every default"). An unknown name raises TypeError, as
    Python does for any unexpected keyword argument; so does, when `prefixes`
    is given, an option of another component (one whose name starts with
    none of them: the C component would silently ignore it). A value out of
    bounds raises InvalidArgumentError (a ValueError) with the library's
    message."""
    if not kwargs:
        return None
    bag = _capi.flt_options_create()
    for name, value in kwargs.items():
        try:
            key = _capi.flt_option_find(name)
        except NotFoundError:
            raise TypeError(
                f"{function}() got an unexpected keyword argument '{name}' "
                f"(libflatline has no option of that name; flatline.options() "
                f"lists them)"
            ) from None
        if prefixes is not None and not name.startswith(prefixes):
            raise TypeError(
                f"{function}() got an unexpected keyword argument '{name}' "
                f"(an option of another component; {function}() reads "
                f"{', '.join(p + '*' for p in prefixes)})"
            )
        _capi.flt_options_set(bag, key, _option_value(function, name, value))
    return bag


def prefixed_options(*prefixes: str) -> Dict[str, OptionInfo]:
    """The options whose names start with one of `prefixes`, in key order."""
    return {name: info for name, info in options().items()
            if name.startswith(prefixes)}


def options_doc(names) -> str:
    """Docstring lines describing the options `names` (in library order)."""
    wanted = set(names)
    lines = []
    for info in options().values():
        if info.name not in wanted:
            continue
        kind = "int" if info.is_integer else "float"
        hi = "inf" if math.isinf(info.max_value) else f"{info.max_value:g}"
        lines.append(
            f"        {info.name} ({kind}): default {info.default:g}, "
            f"range [{info.min_value:g}, {hi}]"
        )
    return "\n".join(lines)
