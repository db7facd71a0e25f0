"""The CNC stand's part programs run (docs/cnc.md): `plclab cnc` (run.py), the bundle for a real
OpenPLC (openplc.py) and the bench. The G-code front end and the tool-path checks they use sit
a layer below the stands, in plclab.nc."""
