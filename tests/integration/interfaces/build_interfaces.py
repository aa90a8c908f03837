"""Build Python bindings for `composition_interfaces` with the rosidl generators from PyPI.

The interface package is not published as a wheel, so the tests generate it from the `.srv`
definitions beside this file (written from the documented field lists) and compile the C
sources with the system compiler against the headers and libraries the ROS wheels install.
Only the Fast DDS C type support is built: rosidl_typesupport_c then links it directly.

    # prints the folder to put on sys.path:
    python tests/integration/interfaces/build_interfaces.py DEST
"""

from __future__ import annotations

import hashlib
import os
import pathlib
import shutil
import subprocess
import sys
import sysconfig
import tempfile

PACKAGE = "composition_interfaces"
HERE = pathlib.Path(__file__).resolve().parent
SOURCE = HERE / PACKAGE
DEPENDENCIES = ["rcl_interfaces", "builtin_interfaces", "service_msgs",
                "type_description_interfaces"]


def _prefix() -> pathlib.Path:
    """The ament prefix that holds the ROS wheels' headers and libraries."""
    candidates = [*os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep), sys.prefix]
    for candidate in candidates:
        if candidate and (pathlib.Path(candidate) / "include" / "rosidl_runtime_c").is_dir():
            return pathlib.Path(candidate)
    raise RuntimeError("no ROS prefix with rosidl headers (install the ROS wheels)")


def fingerprint() -> str:
    digest = hashlib.sha256()
    for path in [*sorted(SOURCE.rglob("*.srv")), pathlib.Path(__file__)]:
        digest.update(path.read_bytes())
    digest.update(sys.version.encode())
    return digest.hexdigest()[:16]


def _generate(out: pathlib.Path, prefix: pathlib.Path) -> None:
    from rosidl_generator_c.cli import GenerateC
    from rosidl_generator_py.cli import GeneratePython
    from rosidl_typesupport_c.cli import GenerateCTypesupport
    from rosidl_typesupport_fastrtps_c.cli import GenerateFastRTPSCTypesupport

    files = [f"{SOURCE}:{p.relative_to(SOURCE)}" for p in sorted((SOURCE / "srv").glob("*.srv"))]
    include = [str(prefix / "share")]
    GenerateC("c").generate(PACKAGE, files, include, out / "c" / PACKAGE)
    GenerateFastRTPSCTypesupport("fastrtps_c").generate(PACKAGE, files, include,
                                                        out / "fastrtps_c" / PACKAGE)
    GenerateCTypesupport("typesupport_c", typesupport_implementations=[
        "rosidl_typesupport_fastrtps_c"]).generate(PACKAGE, files, include, out / "ts_c" / PACKAGE)
    GeneratePython("py", typesupport_implementations=["rosidl_typesupport_c"]).generate(
        PACKAGE, files, include, out / "py" / PACKAGE)


def _compile(compiler: str, sources: list[pathlib.Path], output: pathlib.Path,
             includes: list[pathlib.Path], libs: list[str], lib_dirs: list[pathlib.Path],
             extra: list[str] | None = None) -> None:
    # -O0: the bindings carry a few test requests, and the optimiser took a third of the
    # build (5 of 14 s, most in the Fast DDS type support)
    cmd = [compiler, "-shared", "-fPIC", "-O0", "-w", "-o", str(output),
           *[str(s) for s in sources], *[f"-I{i}" for i in includes],
           *[f"-L{d}" for d in lib_dirs], *[f"-Wl,-rpath,{d}" for d in lib_dirs],
           *[f"-l{lib}" for lib in libs], *(extra or [])]
    if compiler == "g++":
        cmd.insert(1, "-std=c++17")
    result = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if result.returncode != 0:
        raise RuntimeError(f"compiling {output.name} failed:\n{result.stderr[-4000:]}")


def build(dest: pathlib.Path) -> pathlib.Path:
    """Builds (once per definition fingerprint) and returns the folder for sys.path."""
    target = dest / f"{PACKAGE}-{fingerprint()}"
    python_dir = target / "python"
    if (python_dir / PACKAGE / "srv" / "__init__.py").exists():
        return python_dir
    prefix = _prefix()
    # the generators find their templates through the ament index
    os.environ["AMENT_PREFIX_PATH"] = os.pathsep.join(
        p for p in (os.environ.get("AMENT_PREFIX_PATH"), str(prefix)) if p)
    work = pathlib.Path(tempfile.mkdtemp(prefix="rosidl-", dir=dest))
    try:
        gen = work / "gen"
        _generate(gen, prefix)
        lib_dir = work / "lib"
        lib_dir.mkdir()
        inc = prefix / "include"
        includes = [gen / "c", gen / "fastrtps_c", inc, *[inc / d for d in os.listdir(inc)]]
        sys_libs = [prefix / "lib"]
        deps_c = [f"{d}__rosidl_generator_c" for d in DEPENDENCIES]
        deps_fast = [f"{d}__rosidl_typesupport_fastrtps_c" for d in DEPENDENCIES]
        final_lib = target / "lib"
        link_dirs = [*sys_libs, lib_dir, final_lib]
        _compile("gcc", sorted((gen / "c").rglob("*.c")),
                 lib_dir / f"lib{PACKAGE}__rosidl_generator_c.so", includes,
                 ["rosidl_runtime_c", "rcutils", *deps_c], link_dirs)
        _compile("g++", sorted((gen / "fastrtps_c").rglob("*.cpp")),
                 lib_dir / f"lib{PACKAGE}__rosidl_typesupport_fastrtps_c.so", includes,
                 [f"{PACKAGE}__rosidl_generator_c", "rosidl_typesupport_fastrtps_c",
                  "rosidl_typesupport_fastrtps_cpp", "fastcdr", "rmw", "rosidl_runtime_c",
                  "rcutils", *deps_c, *deps_fast], link_dirs)
        _compile("g++", sorted((gen / "ts_c").rglob("*.cpp")),
                 lib_dir / f"lib{PACKAGE}__rosidl_typesupport_c.so", includes,
                 [f"{PACKAGE}__rosidl_typesupport_fastrtps_c", f"{PACKAGE}__rosidl_generator_c",
                  "rosidl_typesupport_c", "rosidl_runtime_c", "rcutils"], link_dirs)
        import numpy

        py_includes = [*includes, pathlib.Path(sysconfig.get_paths()["include"]),
                       pathlib.Path(numpy.get_include())]
        py_gen = gen / "py" / PACKAGE
        deps_py = [f"{d}__rosidl_generator_py" for d in DEPENDENCIES]
        _compile("gcc", sorted(py_gen.rglob("*_s.c")),
                 lib_dir / f"lib{PACKAGE}__rosidl_generator_py.so", py_includes,
                 [f"{PACKAGE}__rosidl_generator_c", "rosidl_runtime_c", "rcutils", *deps_c,
                  *deps_py], link_dirs)
        suffix = sysconfig.get_config_var("EXT_SUFFIX")
        _compile("gcc", sorted(py_gen.glob("_*_s.ep.rosidl_typesupport_c.c")),
                 py_gen / f"{PACKAGE}_s__rosidl_typesupport_c{suffix}", py_includes,
                 [f"{PACKAGE}__rosidl_generator_py", f"{PACKAGE}__rosidl_typesupport_c",
                  f"{PACKAGE}__rosidl_generator_c", "rosidl_runtime_c", "rcutils"], link_dirs)
        for stray in py_gen.rglob("*.c"):
            stray.unlink()
        staged = work / "python"
        staged.mkdir()
        shutil.copytree(py_gen, staged / PACKAGE)
        target.mkdir(parents=True, exist_ok=True)
        shutil.copytree(lib_dir, final_lib, dirs_exist_ok=True)
        # the package appears whole or not at all, even if two test runs build at once
        tmp_python = target / f"python.{os.getpid()}"
        shutil.copytree(staged, tmp_python)
        try:
            tmp_python.rename(python_dir)
        except OSError:
            shutil.rmtree(tmp_python, ignore_errors=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return python_dir


def default_cache() -> pathlib.Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache")
    return pathlib.Path(base) / "tuilaunch-tests"


if __name__ == "__main__":
    where = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else default_cache()
    where.mkdir(parents=True, exist_ok=True)
    print(build(where))
