"""Modbus TCP faces of the soft PLC and OpenPLC's PSM I/O protocol.

protocol  MBAP framing and PDU codec (exception codes 01/02/03 exactly)
profiles  Twido register tables as data (the rules; plclab.stands.twido_profile builds a stand's table)
maps      register maps over the process image: OpenPlcMap, TwidoMap
server    ModbusTcpServer: asyncio in its own thread, never blocking the scan
psm       PSM plant-side server (lockstep), PLC-side client, PlantService, psm_script()
console   the console face: a stand's switches, lamps and readouts on Modbus TCP (and its client)
rawclient a small independent client (tests, bench)
bench     bench_modbus() for `plclab bench`

Nothing is imported here, so `import plclab.modbus.psm` stays cheap and dependency-free.
"""
