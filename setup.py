"""Package layout only (everything else is in pyproject.toml): the Python packages under
harness/, and the repository's top-level plc/ (the one copy of the shipped ST) carried in the
wheel as the package data folder plclab/plc."""
from setuptools import find_packages, setup

setup(
    packages=find_packages("harness") + ["plclab.plc"],
    package_dir={"": "harness", "plclab.plc": "plc"},
)
