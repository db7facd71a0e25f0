"""CNC part programs (docs/cnc.md): the G-code front end that turns a part program into the
frame table of the CNC stand, and the tool-path checks against the interpolators' bounds."""
