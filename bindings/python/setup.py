# SPDX-License-Identifier: Apache-2.0
"""Builds the flatline package by driving CMake on the libflatline source tree.

setuptools (Debian's python3-setuptools) is the build backend; the work is
done by the project's own CMake build, so the wheel holds exactly what ctest
tests: the extension flatline/_capi*.so, SWIG's proxy capi.py and
libflatline.so.N beside them (the extension's rpath is $ORIGIN), and the
testing tier's extension flatline/_testing_capi*.so with
libflatline_testing.so.X.Y.Z (loaded only by `import flatline.testing`).

The coil report (tools/coil_report/coil_report.py and its example rules)
goes in as flatline.coil_report; pyproject.toml makes it and the live view
(flatline.live) the commands flatline-coil-report and flatline-live.

Environment:
    FLATLINE_PREBUILT_PACKAGE  a package folder a CMake build made already
                          (<build>/bindings/python/package/flatline): its
                          files are copied, the libraries stripped of their
                          debug information, and nothing is compiled. The
                          release wheel is made so (packaging/build), from
                          the build the tests ran on.
    FLATLINE_SOURCE_DIR   the libflatline source tree (default: ../.. of this
                          file, i.e. the repository this folder lives in)
    FLATLINE_BUILD_DIR    CMake build directory (default: under setuptools'
                          build_temp, i.e. bindings/python/build/, git-ignored)
    FLATLINE_CMAKE_ARGS   extra arguments for the CMake configure step
    CMAKE_BUILD_PARALLEL_LEVEL  parallel jobs (default 2)
"""

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = Path(__file__).resolve().parent
SOURCE_DIR = Path(os.environ.get("FLATLINE_SOURCE_DIR", HERE.parent.parent)).resolve()


def header_version() -> str:
    """MAJOR.MINOR.PATCH from include/flatline/version.h, the single source."""
    header = SOURCE_DIR / "include" / "flatline" / "version.h"
    if not header.is_file():
        sys.exit(
            f"setup.py: {header} not found; build from a libflatline checkout "
            f"or set FLATLINE_SOURCE_DIR to one"
        )
    text = header.read_text()
    parts = [
        re.search(rf"#define FLT_VERSION_{p} (\d+)", text).group(1)
        for p in ("MAJOR", "MINOR", "PATCH")
    ]
    return ".".join(parts)


class CMakeExtension(Extension):
    """The SWIG extension; CMake builds it, so setuptools compiles nothing."""

    def __init__(self, name: str) -> None:
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext: Extension) -> None:
        prebuilt = os.environ.get("FLATLINE_PREBUILT_PACKAGE")
        if prebuilt:
            built = Path(prebuilt).resolve()
            if not (built / "_capi.so").is_file():
                sys.exit(f"setup.py: FLATLINE_PREBUILT_PACKAGE={prebuilt} holds no _capi.so: "
                         f"build the flt_python_capi target first")
            print(f"setup.py: the package as built in {built}", flush=True)
            self._copy_package(built, strip=True)
            return
        build_dir = Path(
            os.environ.get("FLATLINE_BUILD_DIR", Path(self.build_temp).resolve() / "cmake")
        )
        configure = [
            "cmake",
            "-S", str(SOURCE_DIR),
            "-B", str(build_dir),
            "-DCMAKE_BUILD_TYPE=Release",
            "-DFLT_BUILD_PYTHON=ON",
            "-DFLT_BUILD_CSHARP=OFF",
            "-DFLT_BUILD_TESTS=OFF",
            "-DFLT_BUILD_EXAMPLES=OFF",
            "-DFLT_BUILD_TOOLS=OFF",
            f"-DPython3_EXECUTABLE={sys.executable}",
        ] + shlex.split(os.environ.get("FLATLINE_CMAKE_ARGS", ""))
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", "2")
        build = ["cmake", "--build", str(build_dir), "--target", "flt_python_capi",
                 "-j", jobs]
        for command in (configure, build):
            print("setup.py:", " ".join(shlex.quote(c) for c in command), flush=True)
            subprocess.run(command, check=True)

        self._copy_package(build_dir / "bindings" / "python" / "package" / "flatline",
                           strip=False)

    def _copy_package(self, built: Path, strip: bool) -> None:
        target = Path(self.get_ext_fullpath("flatline._capi"))  # .../flatline/_capi.<abi>.so
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built / "_capi.so", target)
        shutil.copyfile(built / "capi.py", target.parent / "capi.py")
        # The testing tier (flatline.testing over libflatline_testing): its
        # own extension, loaded only by `import flatline.testing`.
        shutil.copyfile(built / "_testing_capi.so",
                        target.parent / target.name.replace("_capi", "_testing_capi", 1))
        shutil.copyfile(built / "testing_capi.py", target.parent / "testing_capi.py")
        # libflatline.so.N is a real file in the package dir (copyfile would
        # follow a symlink anyway): wheels cannot hold symlinks.
        for library in list(built.glob("libflatline.so*")) + list(
                built.glob("libflatline_testing.so*")):
            shutil.copyfile(library, target.parent / library.name)
        # The coil report and its example rules (the live view's default
        # rules too), as the CMake build puts them beside the package.
        for name in ("coil_report.py", "example_rules.json"):
            shutil.copyfile(built / name, target.parent / name)
        # The lookup tables generated from the public headers
        # (bindings/gen_tables.py).
        shutil.copyfile(built / "_tables.py", target.parent / "_tables.py")
        # The licence and the third-party notices travel with the binaries
        # (the package holds libflatline.so, which NOTICE describes).
        for notice in ("LICENSE", "NOTICE"):
            shutil.copyfile(SOURCE_DIR / notice, target.parent / notice)
        strip_tool = shutil.which("strip") if strip else None
        if strip_tool:
            # A RelWithDebInfo build's libflatline is 20+ MB with its debug
            # information, under 2 MB without: the wheel installs in seconds.
            for library in target.parent.glob("*.so*"):
                subprocess.run([strip_tool, "--strip-debug", str(library)], check=True)


setup(
    version=header_version(),
    ext_modules=[CMakeExtension("flatline._capi")],
    cmdclass={"build_ext": CMakeBuild},
    zip_safe=False,
)
