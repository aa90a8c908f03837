"""tuilaunch_demos: installs like an ament_python package (colcon) or with pip into a venv.

Executables go to lib/tuilaunch_demos and launch files to share/tuilaunch_demos, where the
ament index (and so `ros2 run`, `ros2 launch` and tuilaunch) finds them.
"""

from glob import glob

from setuptools import setup

PACKAGE = "tuilaunch_demos"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=[PACKAGE],
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/launch", glob("launch/*.py")),
        (f"share/{PACKAGE}/urdf", glob("urdf/*")),
        (f"share/{PACKAGE}/config", glob("config/*")),
        (f"lib/{PACKAGE}", glob("scripts/*")),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    description="Small Python demo nodes and launch files for tuilaunch",
    license="Apache-2.0",
)
