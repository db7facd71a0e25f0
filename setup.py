"""Package layout only (everything else is in pyproject.toml): the Python packages under
harness/, and the repository's top-level plc/ (the one copy of the shipped ST) carried in the
wheel as the package data folder plclab/plc."""
from setuptools import find_namespace_packages, setup

setup(
    # namespace discovery, as pyproject's packages.find does: the data folders (handouts/,
    # lab/static/, benchprograms/) are packages of the wheel too
    packages=find_namespace_packages("harness", include=["plclab", "plclab.*"], exclude=["*.__pycache__"])
    + ["plclab.plc", "plclab.plc.GVL", "plclab.plc.POUs"],
    package_dir={"": "harness", "plclab.plc": "plc"},
)
