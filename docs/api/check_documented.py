#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Fails unless every public symbol has documentation.

Doxygen (Debian 12's 1.9.4, with WARN_AS_ERROR) already fails on an
undocumented function, type or macro, but it cannot warn about an
undocumented enumerator (that option arrived in a later Doxygen). Every
enumerator of the public headers is a status code, a flag or an option key
that users read, so this script reads Doxygen's XML output and lists each
file member (function, typedef, enum, enumerator, macro) whose brief and
detailed descriptions are both empty. The *_MAX_ENUM_ enumerators are
not values (they keep each enum int-sized) and are skipped.

Usage: check_documented.py XML_DIR
"""
import sys
import xml.etree.ElementTree as ET
from pathlib import Path


def has_text(element) -> bool:
    return element is not None and "".join(element.itertext()).strip() != ""


def documented(member) -> bool:
    return has_text(member.find("briefdescription")) or has_text(
        member.find("detaileddescription"))


def main() -> int:
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    xml_dir = Path(sys.argv[1])
    files = sorted(xml_dir.glob("*_8h.xml"))
    if not files:
        print(f"check_documented: no header XML in {xml_dir}", file=sys.stderr)
        return 2
    missing = []
    checked = 0
    for path in files:
        compound = ET.parse(path).getroot().find("compounddef")
        header = compound.findtext("compoundname")
        for member in compound.iter("memberdef"):
            kind = member.get("kind")
            if kind not in ("function", "typedef", "enum", "define", "variable"):
                continue
            checked += 1
            if not documented(member):
                missing.append(f"{header}: {kind} {member.findtext('name')}")
            if kind != "enum":
                continue
            for value in member.findall("enumvalue"):
                if value.findtext("name").endswith("_MAX_ENUM_"):
                    continue  # not a value: keeps the enum int-sized
                checked += 1
                if not documented(value):
                    missing.append(f"{header}: enumerator {value.findtext('name')} "
                                   f"(of {member.findtext('name')})")
    if missing:
        print("check_documented: these public symbols have no documentation "
              "(a /** ... */ or /**< ... */ comment):", file=sys.stderr)
        for line in missing:
            print("  " + line, file=sys.stderr)
        return 1
    print(f"check_documented: {checked} public symbols in {len(files)} headers, "
          f"all documented")
    return 0


if __name__ == "__main__":
    sys.exit(main())
