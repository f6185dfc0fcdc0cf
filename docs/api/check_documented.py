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

In the headers listed in PARAMETERS_COMPLETE, every function must also
document each parameter (@param) and, unless it returns void, its result
(@return). The list grows header by header until it holds them all; the
others describe their parameters in prose.

Usage: check_documented.py XML_DIR
"""
import sys
import xml.etree.ElementTree as ET
from pathlib import Path


def has_text(element) -> bool:
    return element is not None and "".join(element.itertext()).strip() != ""


# Headers whose functions document every parameter and their result.
PARAMETERS_COMPLETE = {"gauge.h", "genicam.h", "log.h"}


def missing_parameters(member) -> list:
    """The parameters (and "@return") a function's comment leaves out."""
    documented_names = set()
    for name in member.iter("parametername"):
        for part in "".join(name.itertext()).split(","):
            documented_names.add(part.strip())
    missing = []
    for param in member.findall("param"):
        name = param.findtext("declname")
        if name and name not in documented_names:
            missing.append(name)
    returns_void = "".join(member.find("type").itertext()).strip().endswith("void") \
        and "*" not in "".join(member.find("type").itertext())
    has_return = any(sect.get("kind") == "return" for sect in member.iter("simplesect"))
    if not returns_void and not has_return:
        missing.append("@return")
    return missing


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
            elif kind == "function" and header.split("/")[-1] in PARAMETERS_COMPLETE:
                left_out = missing_parameters(member)
                if left_out:
                    missing.append(f"{header}: function {member.findtext('name')} does not "
                                   f"document {', '.join(left_out)}")
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
              "(a /** ... */ or /**< ... */ comment, with @param and @return "
              "in the headers of PARAMETERS_COMPLETE):", file=sys.stderr)
        for line in missing:
            print("  " + line, file=sys.stderr)
        return 1
    print(f"check_documented: {checked} public symbols in {len(files)} headers, "
          f"all documented")
    return 0


if __name__ == "__main__":
    sys.exit(main())
