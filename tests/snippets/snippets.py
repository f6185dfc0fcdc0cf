#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Every fenced code block of the project's Markdown, built, run or checked.

    snippets.py list                          every block and what happens to it
    snippets.py inventory                     tags and markers; sh, json, xml checked
    snippets.py selftest                      the inventory's rules on made-up blocks
    snippets.py c --cc CC --include DIR --lib LIB [--run-env K=V]...
    snippets.py python                        (PYTHONPATH names the package)
    snippets.py csharp --dotnet DOTNET --feed FEED --version V [--rid RID --emulator WINE]

README.md (this folder) explains the markers. A block is never skipped in
silence: one with no language tag, an unknown tag, or a marker without a
reason fails the inventory; each language's command builds (and runs) every
block of its language and fails on the first that does not build or run.
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent

# Tags the runner builds, tags it checks, and tags that say "not code".
BUILT = {"c": "c", "python": "python", "csharp": "csharp"}
CHECKED = {"sh", "json", "xml"}
NOT_CODE = {"text"}  # diagrams, file trees, program output
SKIP_ONLY = {"c++"}  # library internals: allowed only with a skip marker
WRAP_EXT = {"c": ".c", "python": ".py", "csharp": ".cs"}

MARKER = re.compile(r"^\s*<!--\s*snippet:(.*?)-->\s*$")
FENCE = re.compile(r"^(\s*)```(\S*)\s*$")


@dataclass
class Block:
    path: Path
    line: int  # of the opening fence, 1-based
    tag: str
    text: str
    wrap: Optional[str] = None
    no_run: Optional[str] = None  # the reason
    skip: Optional[str] = None  # the reason
    errors: List[str] = field(default_factory=list)

    @property
    def where(self) -> str:
        return f"{self.path.relative_to(ROOT)}:{self.line}"

    @property
    def name(self) -> str:
        stem = re.sub(r"[^A-Za-z0-9]+", "_", str(self.path.relative_to(ROOT).with_suffix("")))
        return f"{stem}_{self.line}"


def markdown_files() -> List[Path]:
    """Every .md of the source tree, build folders and hidden ones left out."""
    found = []
    for dirpath, dirnames, filenames in os.walk(ROOT):
        dirnames[:] = sorted(d for d in dirnames
                             if not d.startswith(".") and not d.startswith("build"))
        found += [Path(dirpath) / f for f in sorted(filenames) if f.endswith(".md")]
    return found


def parse_marker(block: Block, text: str) -> None:
    """`wrap NAME`, `no run: REASON`, `skip: REASON`, joined by ';'."""
    for part in (p.strip() for p in text.split(";")):
        if part.startswith("wrap "):
            block.wrap = part[5:].strip()
        elif part.startswith("no run:"):
            block.no_run = part[7:].strip() or None
            if not block.no_run:
                block.errors.append("'no run:' needs a reason")
        elif part.startswith("skip:"):
            block.skip = part[5:].strip() or None
            if not block.skip:
                block.errors.append("'skip:' needs a reason")
        else:
            block.errors.append(f"unknown marker '{part}' (wrap NAME; no run: REASON; "
                                "skip: REASON)")


def blocks_of(path: Path) -> List[Block]:
    lines = path.read_text(encoding="utf-8").splitlines()
    out = []
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        indent, tag = m.group(1), m.group(2)
        j = i + 1
        while j < len(lines) and not re.match(r"^\s*```\s*$", lines[j]):
            j += 1
        body = [ln[len(indent):] if ln.startswith(indent) else ln for ln in lines[i + 1:j]]
        block = Block(path, i + 1, tag, "\n".join(body) + "\n")
        k = i - 1
        while k >= 0 and not lines[k].strip():
            k -= 1
        if k >= 0:
            mk = MARKER.match(lines[k])
            if mk:
                parse_marker(block, mk.group(1))
        if not tag:
            block.errors.append("no language tag: give it one (text for diagrams, trees "
                                "and output)")
        elif tag in SKIP_ONLY and not block.skip:
            block.errors.append(f"'{tag}' blocks are not built: mark it 'skip: REASON'")
        elif tag not in BUILT and tag not in CHECKED and tag not in NOT_CODE | SKIP_ONLY:
            block.errors.append(f"unknown language tag '{tag}' (built: "
                                f"{', '.join(BUILT)}; checked: {', '.join(sorted(CHECKED))}; "
                                "text)")
        elif tag in BUILT and block.wrap:
            wrap = HERE / "wrap" / (block.wrap + WRAP_EXT[tag])
            if not wrap.is_file():
                block.errors.append(f"wrap '{block.wrap}': {wrap.relative_to(ROOT)} is missing")
        elif tag not in BUILT and (block.wrap or block.no_run):
            block.errors.append(f"'{tag}' blocks are not built: wrap and no run do not apply")
        out.append(block)
        i = j + 1
    return out


def all_blocks() -> List[Block]:
    return [b for p in markdown_files() for b in blocks_of(p)]


def fail(block: Block, what: str, output: str = "") -> None:
    print(f"FAIL {block.where} ({block.tag}): {what}")
    if output:
        print(output.rstrip())


# --- wrapping ------------------------------------------------------------------

def split_hoisted(block: Block) -> (str, str):
    """The lines that must stand at the top of a file (C preprocessor lines,
    C# using directives) and the rest."""
    top, rest = [], []
    continued = False
    for ln in block.text.splitlines():
        if block.tag == "c" and (continued or ln.lstrip().startswith("#")):
            top.append(ln)
            continued = ln.rstrip().endswith("\\")
        elif block.tag == "csharp" and re.match(r"^using\s+[A-Za-z_.]+\s*;", ln):
            top.append(ln)
        else:
            rest.append(ln)
    return "\n".join(top) + "\n", "\n".join(rest) + "\n"


def wrapped(block: Block, marker: str) -> str:
    """The block inside its wrap (the line holding `marker` replaced)."""
    top, body = split_hoisted(block)
    if not block.wrap:
        return block.text
    wrap = (HERE / "wrap" / (block.wrap + WRAP_EXT[block.tag])).read_text(encoding="utf-8")
    if marker not in wrap:
        raise SystemExit(f"wrap {block.wrap}: no '{marker}' line")
    head, _, tail = wrap.partition(marker)
    head = head[:head.rfind("\n") + 1]
    # a hoisted line the wrap has already (a using, an include) is left out
    top = "".join(ln + "\n" for ln in top.splitlines() if ln.strip() and ln not in wrap)
    tail = tail[tail.find("\n") + 1:]
    return top + head + body + tail


def run(cmd: List[str], cwd: Path, env: Optional[Dict[str, str]] = None,
        timeout: int = 600) -> subprocess.CompletedProcess:
    return subprocess.run(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=timeout)


def work_dir(name: str) -> Path:
    base = Path(os.environ.get("FLT_SNIPPETS_WORK", tempfile.gettempdir())) / name
    shutil.rmtree(base, ignore_errors=True)
    base.mkdir(parents=True)
    return base


def blocks_to_build(tag: str) -> List[Block]:
    blocks = [b for b in all_blocks() if b.tag == tag]
    bad = [b for b in blocks if b.errors]
    for b in bad:
        fail(b, "; ".join(b.errors))
    if bad:
        sys.exit(1)
    for b in blocks:
        if b.skip:
            print(f"skip {b.where}: {b.skip}")
    return [b for b in blocks if not b.skip]


def summary(tag: str, built: int, ran: int, skipped: int, failed: int) -> int:
    print(f"{tag} snippets: {built} built, {ran} of them run, {skipped} skipped "
          f"with a reason, {failed} failed")
    return 1 if failed or built == 0 else 0


# --- the languages -----------------------------------------------------------------

def cmd_c(args: argparse.Namespace) -> int:
    blocks = blocks_to_build("c")
    work = work_dir("snippets-c")
    built = ran = failed = 0
    env = dict(os.environ, FLT_SOURCE_DIR=str(ROOT))
    for kv in args.run_env or []:
        k, _, v = kv.partition("=")
        env[k] = v
    # (Linux: the library found where it was built)
    rpath = [] if args.emulator else [f"-Wl,-rpath,{Path(args.lib).resolve().parent}"]
    for b in blocks:
        src = work / (b.name + ".c")
        src.write_text(wrapped(b, "/* SNIPPET */"), encoding="utf-8")
        exe = work / (b.name + (".exe" if args.emulator else ""))
        cc = run(args.cc.split() + ["-std=c99", "-Wall", "-Wextra", "-Werror",
                                    f"-I{Path(args.include).resolve()}", f"-I{HERE / 'wrap'}", str(src), "-o", str(exe), args.lib,
                                    "-lm"] + rpath, work)
        if cc.returncode:
            fail(b, "does not compile", cc.stdout + f"\n(the source: {src})")
            failed += 1
            continue
        built += 1
        if b.no_run:
            print(f"ok   {b.where}: built (not run: {b.no_run})")
            continue
        exe_cmd = ([args.emulator] if args.emulator else []) + [str(exe)]
        r = run(exe_cmd, work, env)
        if r.returncode:
            fail(b, f"exits with {r.returncode}", r.stdout)
            failed += 1
            continue
        ran += 1
        print(f"ok   {b.where}: built and run")
    return summary("C", built, ran, len([x for x in all_blocks() if x.tag == "c" and x.skip]),
                   failed)


def cmd_python(args: argparse.Namespace) -> int:
    blocks = blocks_to_build("python")
    work = work_dir("snippets-python")
    built = ran = failed = 0
    for b in blocks:
        src = work / (b.name + ".py")
        src.write_text(wrapped(b, "# SNIPPET"), encoding="utf-8")
        try:
            compile(src.read_text(encoding="utf-8"), str(src), "exec")
        except SyntaxError as e:
            fail(b, f"does not compile: {e}")
            failed += 1
            continue
        built += 1
        if b.no_run:
            print(f"ok   {b.where}: compiled (not run: {b.no_run})")
            continue
        r = run([sys.executable, "-W", "error::DeprecationWarning", str(src)], work,
                dict(os.environ, FLT_SOURCE_DIR=str(ROOT)))
        if r.returncode:
            fail(b, f"exits with {r.returncode}", r.stdout + f"\n(the source: {src})")
            failed += 1
            continue
        ran += 1
        print(f"ok   {b.where}: run")
    return summary("Python", built, ran,
                   len([x for x in all_blocks() if x.tag == "python" and x.skip]), failed)


CSPROJ = """<Project Sdk="Microsoft.NET.Sdk">
  <PropertyGroup>
    <OutputType>Exe</OutputType>
    <TargetFramework>net10.0</TargetFramework>
    <Nullable>enable</Nullable>
    <ImplicitUsings>disable</ImplicitUsings>
    <LangVersion>latest</LangVersion>
    <TreatWarningsAsErrors>true</TreatWarningsAsErrors>
    <AllowUnsafeBlocks>false</AllowUnsafeBlocks>
    <RestoreAdditionalProjectSources>{sources}</RestoreAdditionalProjectSources>
    <RestorePackagesPath>{packages}</RestorePackagesPath>
  </PropertyGroup>
  <ItemGroup>
    <PackageReference Include="Flatline" Version="{version}" />
  </ItemGroup>
</Project>
"""


def cmd_csharp(args: argparse.Namespace) -> int:
    """One program: each block a class of its own (Snippet_<file>_<line>.Run),
    the main program runs those that run, each in a fresh folder."""
    blocks = blocks_to_build("csharp")
    work = work_dir("snippets-csharp" + ("-" + args.rid if args.rid else ""))
    project = work / "project"
    project.mkdir()
    packages = work / "packages"
    sources = ";".join([args.feed] + [s for s in (args.extra_sources or "").replace("%3B", ";").split(";") if s])
    (project / "Snippets.csproj").write_text(CSPROJ.format(
        sources=sources, packages=packages, version=args.version), encoding="utf-8")
    # An empty Directory.Build.props stops the search for the tree's.
    (project / "Directory.Build.props").write_text("<Project />\n", encoding="utf-8")
    calls = []
    for b in blocks:
        top, body = split_hoisted(b)
        if b.wrap:
            inner = wrapped(b, "// SNIPPET")
            # wrapped() put the hoisted lines first; the wrap holds the class.
            text = inner.replace("class Snippet", f"class {b.name}", 1)
        else:
            usings = "".join(u + "\n" for u in ("using System;", "using Flatline;")
                             if u not in top)
            text = (usings + top + f"static class {b.name}\n{{\n    public static void Run()\n    {{\n"
                    + body + "    }\n}\n")
        if f"class {b.name}" not in text:
            raise SystemExit(f"wrap {b.wrap}: no 'class Snippet'")
        (project / (b.name + ".cs")).write_text(f"// {b.where}\n" + text, encoding="utf-8")
        if not b.no_run:
            calls.append(b)
    main = ["using System;", "using System.IO;", "", "static class SnippetsMain", "{",
            "    static int Main()", "    {", "        string root = Directory.GetCurrentDirectory();"]
    for b in calls:
        main += [f"        Console.WriteLine(\"run  {b.where}\");",
                 f"        Directory.CreateDirectory(Path.Combine(root, \"{b.name}\"));",
                 f"        Directory.SetCurrentDirectory(Path.Combine(root, \"{b.name}\"));",
                 f"        {b.name}.Run();",
                 f"        Console.WriteLine(\"ok   {b.where}: built and run\");"]
    main += ["        return 0;", "    }", "}"]
    (project / "SnippetsMain.cs").write_text("\n".join(main) + "\n", encoding="utf-8")

    env = dict(os.environ, DOTNET_CLI_TELEMETRY_OPTOUT="1", DOTNET_NOLOGO="1",
               DOTNET_SKIP_FIRST_TIME_EXPERIENCE="1", DOTNET_CLI_USE_MSBUILD_SERVER="0",
               MSBUILDDISABLENODEREUSE="1")
    common = ["-nodeReuse:false", "--disable-build-servers", "-c", "Release"]
    if args.rid:
        build = [args.dotnet, "publish", str(project), "-r", args.rid, "--self-contained",
                 "-o", str(work / "out")] + common
        program = [args.emulator, str(work / "out" / "Snippets.exe")]
    else:
        build = [args.dotnet, "build", str(project), "-o", str(work / "out")] + common
        program = [args.dotnet, str(work / "out" / "Snippets.dll")]
    r = run(build, project, env, timeout=1200)
    if r.returncode:
        print(r.stdout.rstrip())
        # name the blocks the compiler complained about
        for b in blocks:
            if b.name + ".cs" in r.stdout:
                fail(b, "does not compile (above)")
        return summary("C#", 0, 0, 0, len(blocks))
    for b in blocks:
        if b.no_run:
            print(f"ok   {b.where}: built (not run: {b.no_run})")
    rundir = work / "run"
    rundir.mkdir()
    r = run(program, rundir, env, timeout=1200)
    print(r.stdout.rstrip())
    failed = 1 if r.returncode else 0
    ran = r.stdout.count(": built and run")
    if failed:
        print(f"FAIL the snippets program exits with {r.returncode}")
    return summary("C#", len(blocks), ran,
                   len([x for x in all_blocks() if x.tag == "csharp" and x.skip]), failed)


def cmd_inventory(args: argparse.Namespace) -> int:
    blocks = all_blocks()
    failed = 0
    counts: Dict[str, int] = {}
    for b in blocks:
        counts[b.tag or "(none)"] = counts.get(b.tag or "(none)", 0) + 1
        if b.errors:
            fail(b, "; ".join(b.errors))
            failed += 1
            continue
        if b.skip or b.tag in BUILT or b.tag in NOT_CODE:
            continue
        problem = None
        if b.tag == "sh":
            r = subprocess.run(["bash", "-n"], input=b.text, text=True,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
            problem = r.stdout if r.returncode else None
        elif b.tag == "json":
            try:
                json.loads(b.text)
            except ValueError as e:
                problem = str(e)
        elif b.tag == "xml":
            try:  # a fragment: elements of a project file
                ElementTree.fromstring("<fragment>" + b.text + "</fragment>")
            except ElementTree.ParseError as e:
                problem = str(e)
        if problem:
            fail(b, "does not parse", problem)
            failed += 1
    print("blocks by tag: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
    print(f"inventory: {len(blocks)} blocks in {len(markdown_files())} files, "
          f"{sum(1 for b in blocks if b.skip)} skipped with a reason, {failed} failed")
    return 1 if failed else 0


def cmd_selftest(args: argparse.Namespace) -> int:
    """The inventory's rules on a Markdown file made for the purpose: each
    way of leaving a block unaccounted for is caught, a proper one is not."""
    cases = [
        ("```\nx\n```\n", "no language tag"),
        ("```rust\nfn main() {}\n```\n", "unknown language tag"),
        ("<!-- snippet: skip: -->\n```c\nint x;\n```\n", "'skip:' needs a reason"),
        ("<!-- snippet: no run: -->\n```python\npass\n```\n", "'no run:' needs a reason"),
        ("<!-- snippet: wrap no_such_wrap -->\n```c\nint x;\n```\n", "is missing"),
        ("<!-- snippet: maybe -->\n```c\nint x;\n```\n", "unknown marker"),
        ("```c++\nint x;\n```\n", "mark it 'skip: REASON'"),
        ("<!-- snippet: wrap recon_rows -->\n```json\n{}\n```\n", "do not apply"),
        ("<!-- snippet: no run: needs a camera -->\n```python\npass\n```\n", None),
        ("```text\na diagram\n```\n", None),
    ]
    failed = 0
    with tempfile.TemporaryDirectory() as tmp:
        for i, (text, want) in enumerate(cases):
            md = Path(tmp) / f"case{i}.md"
            md.write_text("Some prose.\n\n" + text, encoding="utf-8")
            errors = "; ".join(e for b in blocks_of(md) for e in b.errors)
            ok = (want in errors) if want else not errors
            print(f"{'ok  ' if ok else 'FAIL'} case {i}: {errors or 'accepted'}")
            failed += not ok
    print(f"selftest: {len(cases) - failed} of {len(cases)} cases as expected")
    return 1 if failed else 0


def cmd_list(args: argparse.Namespace) -> int:
    for b in all_blocks():
        what = ("skip: " + b.skip if b.skip else
                "built" + (" (wrap " + b.wrap + ")" if b.wrap else "")
                + (", not run: " + b.no_run if b.no_run else ", run") if b.tag in BUILT else
                "checked" if b.tag in CHECKED else "text" if b.tag in NOT_CODE else "ERROR")
        print(f"{b.where:45} {b.tag or '-':8} {what}" + ("  " + "; ".join(b.errors)
                                                          if b.errors else ""))
    return 0


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    sub.add_parser("list")
    sub.add_parser("inventory")
    sub.add_parser("selftest")
    c = sub.add_parser("c")
    c.add_argument("--cc", required=True)
    c.add_argument("--include", required=True)
    c.add_argument("--lib", required=True)
    c.add_argument("--emulator")
    c.add_argument("--run-env", action="append")
    sub.add_parser("python")
    cs = sub.add_parser("csharp")
    cs.add_argument("--dotnet", required=True)
    cs.add_argument("--feed", required=True)
    cs.add_argument("--version", required=True)
    cs.add_argument("--extra-sources")
    cs.add_argument("--rid")
    cs.add_argument("--emulator")
    args = p.parse_args()
    return {"list": cmd_list, "inventory": cmd_inventory, "selftest": cmd_selftest, "c": cmd_c, "python": cmd_python,
            "csharp": cmd_csharp}[args.command](args)


if __name__ == "__main__":
    sys.exit(main())
