"""Plant models ("digital twins") of the lab stands.

Plants are plain classes (see base.PlantModel): they read PLC outputs and return PLC inputs
by OpenPLC location name, and know nothing of ST, sockets or clocks. This package must import
with the Python standard library only: OpenPLC runs our PSM script in its own virtualenv.
"""
from __future__ import annotations

import importlib

STANDS = ("mp9c", "tur10", "thermo", "cnc")


def make_plant(stand: str, **params):
    """A fresh plant model of `stand` with its default parameters (overridable by keyword)."""
    if stand not in STANDS:
        raise ValueError(f"unknown stand {stand!r} (one of {', '.join(STANDS)})")
    module = importlib.import_module(f"plclab.plants.{stand}")
    return module.create(**params)


def psm_plant(stand: str):
    """The plant model a PSM script runs (same object as in-process)."""
    return make_plant(stand)
