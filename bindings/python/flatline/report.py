# SPDX-License-Identifier: Apache-2.0
"""The coil report from an archive: ``python -m flatline.report ARCHIVE
[--coil ID] [--out DIR]`` (flatline.coil_report, tools/coil_report in the
source tree, does the work; ``--help`` lists the options)."""

from __future__ import annotations

import sys

from .coil_report import list_coils, main, read_coil, write_reports

__all__ = ["main", "read_coil", "list_coils", "write_reports"]

if __name__ == "__main__":
    sys.exit(main())
