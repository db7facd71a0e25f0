"""The native scan path: a program's C (plclab.runtime.cgen), built once, run by the PLC.

Where a C compiler is present (`cc`, or $CC) and the program uses only what the C backend
covers, the PLC scans in C: the variables live in C structs and the Python objects the rest
of the runtime sees (program instances, the globals, FB instances, arrays, structures) are
mirrors that read and write that memory. So watching, forcing, writing by name, the I/O image
exchange, retain save and restore, tracing and online monitoring work as on the Python path,
unchanged; the values are the same because the C computes what the Python path computes
(cgen's docstring). Where there is no compiler, the build fails, or the backend does not
cover the program, the Python path runs (silently; one line on stderr when PLCLAB_NATIVE=1
asked for native).

Turning it off: PLCLAB_NATIVE=0 in the environment, `PLC(..., native=False)`, or
`python_only()` around the code that must see Python frames (the grader's line tracer). Built libraries are cached by the hash of their C
in $XDG_CACHE_HOME/plclab/native (default ~/.cache/plclab/native); a build writes a temporary
file and renames it, so concurrent processes never load a half-written library.
"""
from __future__ import annotations

import contextlib
import contextvars
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any, Iterator, Optional

from plclab.iec import types as T
from plclab.runtime.cgen import FAULT_KINDS, CProgram, Layout, Unsupported, emit_c
from plclab.runtime.faults import PlcFault

ENV = "PLCLAB_NATIVE"
CFLAGS = ("-O2", "-shared", "-fPIC", "-fwrapv", "-ffp-contract=off", "-fno-fast-math", "-std=gnu11")
"""-fwrapv: signed overflow wraps (as the Python path wraps); -ffp-contract=off: no fused
multiply-add, every float operation rounds once."""
BUILD_TIMEOUT_S = 120

_PYTHON_ONLY: contextvars.ContextVar[bool] = contextvars.ContextVar("plclab_python_only", default=False)
_told: set[str] = set()
_FAILED = object()


@contextlib.contextmanager
def python_only() -> Iterator[None]:
    """PLCs created inside the block run the Python path (e.g. under a line tracer)."""
    token = _PYTHON_ONLY.set(True)
    try:
        yield
    finally:
        _PYTHON_ONLY.reset(token)


def setting() -> Optional[bool]:
    """What the user asked: True (PLCLAB_NATIVE=1), False (PLCLAB_NATIVE=0), None (nothing:
    native where it can run)."""
    env = os.environ.get(ENV, "").strip().lower()
    if env in ("0", "false", "no", "off"):
        return False
    if env in ("1", "true", "yes", "on"):
        return True
    return None


def wanted(requested: Optional[bool] = None) -> bool:
    if _PYTHON_ONLY.get() or requested is False:
        return False
    return setting() is not False


def _inform(key: str, message: str) -> None:
    """One line, once per process, and only when the user asked for native."""
    if setting() is True and key not in _told:
        _told.add(key)
        print(f"plclab: {message}; the Python path runs", file=sys.stderr)


def cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "plclab" / "native"


def c_compiler() -> Optional[str]:
    cc = os.environ.get("CC")
    if cc and shutil.which(cc):
        return shutil.which(cc)
    for name in ("cc", "gcc", "clang"):
        found = shutil.which(name)
        if found:
            return found
    return None


def build(source: str) -> Optional[Path]:
    """The shared library of `source`, from the cache or compiled now; None without a
    compiler or when the build fails."""
    cc = c_compiler()
    if cc is None:
        _inform("cc", "no C compiler (cc) found for the native scan path")
        return None
    key = hashlib.sha256("\0".join((source, cc, *CFLAGS)).encode()).hexdigest()[:32]
    out_dir = cache_dir()
    lib = out_dir / f"plc_{key}.so"
    if lib.exists():
        return lib
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        work = Path(tempfile.mkdtemp(prefix="build-", dir=out_dir))
    except OSError as e:
        _inform("cache", f"cannot write the native cache {out_dir}: {e.strerror}")
        return None
    try:
        src = work / "plc.c"
        src.write_text(source)
        tmp_lib = work / "plc.so"
        r = subprocess.run([cc, *CFLAGS, "-o", str(tmp_lib), str(src), "-lm"], capture_output=True,
                           text=True, timeout=BUILD_TIMEOUT_S)
        if r.returncode != 0:
            first = (r.stderr.strip().splitlines() or ["?"])[0]
            _inform("build", f"the native build failed ({first})")
            return None
        os.replace(tmp_lib, lib)          # atomic: another process sees all of it or nothing
        return lib
    except (OSError, subprocess.SubprocessError) as e:
        _inform("build", f"the native build failed ({e})")
        return None
    finally:
        shutil.rmtree(work, ignore_errors=True)


def program_for(compiled: Any) -> Optional["NativeProgram"]:
    """The native program of a compiled (Python path) program, built once per compiled
    program; None when native cannot run it."""
    cached = getattr(compiled, "_native", None)
    if cached is _FAILED:
        return None
    if cached is not None:
        return cached
    result: Any = _FAILED
    try:
        cprog = emit_c(compiled.checked)
    except Unsupported as e:
        _inform(f"unsupported:{e}", f"the native scan path does not cover {e}")
        cprog = None
    if cprog is not None:
        lib = build(cprog.source)
        if lib is not None:
            try:
                result = NativeProgram(cprog, lib)
            except Exception as e:        # cffi refused the declarations: a bug of cgen
                _inform("load", f"the native library did not load ({e})")
    try:
        compiled._native = result
    except AttributeError:
        pass
    return None if result is _FAILED else result


class NativeProgram:
    """A loaded native library and the mirror classes of its structs."""

    def __init__(self, cprog: CProgram, lib_path: Path):
        import cffi
        self.cprog = cprog
        self.ffi = cffi.FFI()
        self.ffi.cdef(cprog.cdef)
        self.lib = self.ffi.dlopen(str(lib_path))
        self._classes: dict[tuple[str, Any], type] = {}

    def attach(self, plc: Any) -> Any:
        """Fresh C state for `plc`: every variable takes the value the Python path just
        initialised it to (so initial values, FB initialisers and retain restore are the
        Python path's own), and the PLC's instances and globals become mirrors of it."""
        ffi, lib, cprog = self.ffi, self.lib, self.cprog
        st = ffi.new("State *")
        keep = [st]
        g = self.mirror(cprog.layouts["GLOBALS"], st.g, plc.compiled.namespace["G"], keep)
        sites = cprog.sites
        for inst in plc.instances:
            key = type(inst.obj)._ST_NAME.upper()
            sname = cprog.program_structs[key]
            p = ffi.new(f"{sname} *")
            keep.append(p)
            proxy = self.mirror(cprog.layouts[sname], p[0], inst.obj, keep)
            proxy._run = _runner(getattr(lib, cprog.run_functions[key]), st, p, plc, sites)
            inst.obj = proxy
        plc._native_keep = keep
        return g

    def mirror(self, layout: Layout, cdata: Any, pyobj: Any, keep: list) -> Any:
        cls = self._class(layout, type(pyobj), pyobj)
        proxy = cls.__new__(cls)
        _init_proxy(self, proxy, layout, cdata, pyobj, keep)
        return proxy

    def _class(self, layout: Layout, pytype: type, pyobj: Any) -> type:
        key = (layout.cname, pytype)
        cls = self._classes.get(key)
        if cls is None:
            cls = _make_class(layout, pytype, pyobj)
            self._classes[key] = cls
        return cls


def _runner(fn: Any, st: Any, p: Any, plc: Any, sites: list) -> Any:
    clock = plc.scan_clock

    def run() -> None:
        rc = fn(st, p, clock.now, plc.watchdog_s)
        if rc:
            raise _fault(rc, st, sites, plc)
    return run


def _fault(rc: int, st: Any, sites: list, plc: Any) -> PlcFault:
    kind = FAULT_KINDS[rc] if 0 < rc < len(FAULT_KINDS) else "internal"
    a, b, c = st.fault_a, st.fault_b, st.fault_c
    if kind == "division_by_zero":
        message = "integer division by zero"
    elif kind == "division_overflow":
        message = f"{'DINT' if b == 32 else 'LINT'} {a} {'MOD' if c else '/'} -1 overflows (SIGFPE on x86)"
    elif kind == "index_out_of_range":
        message = f"array index {a} outside {b}..{c}"
    elif kind == "watchdog":
        message = f"scan exceeded the watchdog limit of {plc.watchdog_s:g} s (endless loop?)"
    else:
        message = f"native fault code {rc}"
    exc = PlcFault(kind, message)
    site = st.fault_site
    exc.st_where = sites[site] if 0 < site < len(sites) else None
    return exc


# --------------------------------------------------------------------------- mirrors

class ArrayMirror(list):
    """An ARRAY in C memory, seen as the Python path's flat list (a list, so the runtime's
    `isinstance(x, list)` tests take it for an array)."""

    __slots__ = ("_a", "_n", "_items")

    def __len__(self) -> int:
        return self._n

    def __getitem__(self, i: Any) -> Any:
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(self._n))]
        if i < 0:
            i += self._n
        items = self._items
        return items[i] if items is not None else self._a[i]

    def __setitem__(self, i: Any, v: Any) -> None:
        if isinstance(i, slice):
            for j, x in zip(range(*i.indices(self._n)), v):
                self[j] = x
            return
        if i < 0:
            i += self._n
        items = self._items
        if items is not None:
            _assign(items[i], v)
        else:
            self._a[i] = v

    def __iter__(self) -> Iterator[Any]:
        return iter(self._items) if self._items is not None else iter(self._a)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, list) and len(other) == self._n and all(x == y for x, y in zip(self, other))

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return repr(list(iter(self)))


class StructMirror(T.StructValue):
    """A STRUCT value in C memory, seen as the Python path's StructValue."""

    __slots__ = ("_p", "_k", "_names")

    @property
    def __dict__(self) -> dict:  # type: ignore[override]
        return {n: getattr(self, n) for n in self._names}


def _assign(dst: Any, value: Any) -> None:
    """Copy an ARRAY / STRUCT / FB value into the C memory a mirror shows."""
    if isinstance(dst, ArrayMirror):
        if dst._items is None:
            dst._a[0:dst._n] = list(value)
        else:
            for d, v in zip(dst._items, value):
                _assign(d, v)
        return
    for name in dst._names:
        sub = dst._k.get(name)
        v = getattr(value, name)
        if sub is not None:
            _assign(sub, v)
        else:
            setattr(dst, name, v)


def _make_class(layout: Layout, pytype: type, pyobj: Any) -> type:
    names = [f.name for f in layout.fields if f.kind != "ref" and hasattr(pyobj, f.name)]
    lines = []
    for f in layout.fields:
        if f.name not in names:
            continue
        if f.kind == "scalar":
            lines += [f"    @property\n    def {f.name}(self): return self._p.{f.cname}",
                      f"    @{f.name}.setter\n    def {f.name}(self, v): self._p.{f.cname} = v"]
        else:
            lines += [f"    @property\n    def {f.name}(self): return self._k['{f.name}']",
                      f"    @{f.name}.setter\n    def {f.name}(self, v): _assign(self._k['{f.name}'], v)"]
    is_struct = layout.kind == "struct"
    base = "StructMirror" if is_struct else "object"
    slots = "()" if is_struct else "('_p', '_k', '_names', '_run', '__weakref__')"
    src = f"class Mirror({base}):\n    __slots__ = {slots}\n" + "\n".join(lines) + "\n"
    if not is_struct:
        src += "    def __call__(self):\n        raise TypeError('a native block is called by the C code')\n"
    ns: dict[str, Any] = {"StructMirror": StructMirror, "_assign": _assign}
    exec(compile(src, f"<plc-native-{layout.cname}>", "exec"), ns)
    cls = ns["Mirror"]
    cls.__name__ = cls.__qualname__ = getattr(pytype, "__name__", layout.cname)
    if not is_struct:
        # what the runtime reads of a program / block class: its variables and ST name
        cls.__slots__ = getattr(pytype, "__slots__", tuple(names))
        cls._ST_NAME = getattr(pytype, "_ST_NAME", layout.st_name)
    return cls


def _init_proxy(np: NativeProgram, proxy: Any, layout: Layout, cdata: Any, pyobj: Any, keep: list) -> None:
    cls = type(proxy)
    names = [f.name for f in layout.fields if f.kind != "ref" and hasattr(pyobj, f.name)]
    proxy._p = cdata
    proxy._names = names
    kids: dict[str, Any] = {}
    proxy._k = kids
    for f in layout.fields:
        if f.name not in names:
            continue
        value = getattr(pyobj, f.name)
        if f.kind == "scalar":
            setattr(cdata, f.cname, value)
        elif f.kind in ("struct", "fb"):
            kids[f.name] = np.mirror(np.cprog.layouts[f.sub], getattr(cdata, f.cname), value, keep)
        elif f.kind == "array":
            arr = getattr(cdata, f.cname)
            m = ArrayMirror()
            m._a, m._n = arr, f.size
            if f.sub_kind == "scalar":
                m._items = None
                arr[0:f.size] = list(value)
            else:
                sub = np.cprog.layouts[f.sub]
                m._items = [np.mirror(sub, arr[i], value[i], keep) for i in range(f.size)]
            kids[f.name] = m
    del cls


__all__ = ["ENV", "NativeProgram", "build", "cache_dir", "program_for", "python_only", "setting", "wanted"]
