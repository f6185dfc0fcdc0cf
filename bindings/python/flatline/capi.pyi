# SPDX-License-Identifier: Apache-2.0
# The raw SWIG layer (generated capi.py over _capi.so). Internal: use the
# flatline package's classes. Listed so type checkers accept its use there.
from typing import Any

def __getattr__(name: str) -> Any: ...
