"""Numerical-control part programs: the G-code front end (gcode: a part program -> the frame
table the CNC stand runs) and the tool-path geometry every frame is checked against (toolpath).

A language front end like frontend/ is for ST: below the stands, which load part programs into
their frame tables; it knows nothing of the stands, the plant or the PLC.
"""
