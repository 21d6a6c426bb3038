"""Shared fixtures of the Python tests (run by ctest: tests/CMakeLists.txt sets PYTHONPATH to
build/python and LAMBERT_BIN to the CLI built beside the module)."""
import os
import subprocess

import pytest

import lambert

LAMBERT_BIN = os.environ.get("LAMBERT_BIN", "build/bin/lambert")


def run_cli(*args, cwd=None):
    """Runs the lambert CLI; fails the test with its stderr when it does not exit 0."""
    p = subprocess.run([LAMBERT_BIN, *map(str, args)], capture_output=True, text=True, cwd=cwd)
    assert p.returncode == 0, f"lambert {' '.join(map(str, args))}: {p.stderr}"
    return p


@pytest.fixture(scope="session")
def cornell():
    return lambert.load_scene()


@pytest.fixture(scope="session")
def cornell_mesh(cornell):
    return cornell.mesh(patches=200)


def write_obj(path, groups, mtl=None):
    """Writes an OBJ of named groups, each a list of polygons (lists of (x, y, z)); `mtl` maps
    a group to (Kd, Ke) and goes into a material library beside it."""
    lines, k = [], 1
    if mtl:
        lib = os.path.splitext(path)[0] + ".mtl"
        with open(lib, "w") as f:
            for name, (kd, ke) in mtl.items():
                f.write(f"newmtl m_{name}\nKd {kd[0]} {kd[1]} {kd[2]}\nKe {ke[0]} {ke[1]} {ke[2]}\n")
        lines.append(f"mtllib {os.path.basename(lib)}")
    for name, polygons in groups.items():
        lines.append(f"g {name}")
        if mtl:
            lines.append(f"usemtl m_{name}")
        for poly in polygons:
            for x, y, z in poly:
                lines.append(f"v {x} {y} {z}")
            lines.append("f " + " ".join(str(k + i) for i in range(len(poly))))
            k += len(poly)
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    return str(path)
