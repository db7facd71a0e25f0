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
`python_only()` around the code that must see Python frames (the grader's line tracer).
Built libraries are cached by the hash of their C in $XDG_CACHE_HOME/plclab/native (default
~/.cache/plclab/native), at most CACHE_MAX_BYTES of them (least recently used go first); a
build writes a temporary file and renames it, so concurrent processes never load a
half-written library. User-facing: docs/runtime.md.
"""
from __future__ import annotations

import contextlib
import contextvars
import hashlib
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import threading
import time
import weakref
from pathlib import Path
from typing import Any, Callable, Iterator, Optional, Sequence

from plclab.fileio import user_cache_dir
from plclab.iec import types as T
from plclab.runtime.cgen import FAULT_KINDS, CProgram, Layout, Unsupported, emit_c
from plclab.runtime.faults import PlcFault
from plclab.runtime.gencode import define

ENV = "PLCLAB_NATIVE"
_LIBM = ("sin", "cos", "tan", "asin", "acos", "atan", "exp", "log", "log10", "pow")
CFLAGS = ("-O1", "-shared", "-fPIC", "-fwrapv", "-ffp-contract=off", "-fno-fast-math", "-std=gnu11",
          *(f"-fno-builtin-{f}{suffix}" for f in _LIBM for suffix in ("", "f")))
"""-fwrapv: signed overflow wraps (as the Python path wraps); -ffp-contract=off: no fused
multiply-add, every float operation rounds once; -fno-builtin-sinf & co: gcc would compute a
call on constants itself, correctly rounded, where OpenPLC and the Python path call the C
library (powf(1.0574875, -2.4471879) differs in the last place)."""
BUILD_TIMEOUT_S = 120
CACHE_MAX_BYTES = 256 * 1024 * 1024
"""What the built libraries may take together: a class graded term after term, or a test
suite run day after day, builds new programs every time. Past it, the libraries used least
recently go (a load marks a library used); a program whose library went is built again."""
STALE_BUILD_S = 3600      # a build folder this old belongs to a build that died

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


def for_plc(compiled: Any, requested: Optional[bool] = None) -> Optional["NativeProgram"]:
    """What a PLC loading `compiled` scans with: a NativeProgram, or None for the Python
    path. `requested` True (or PLCLAB_NATIVE=1) builds now and waits; None builds in the
    background once the program is loaded a second time (program_for)."""
    if not wanted(requested):
        return None
    return program_for(compiled, wait=requested is True or setting() is True)


def _inform(key: str, message: str) -> None:
    """One line, once per process, and only when the user asked for native."""
    if setting() is True and key not in _told:
        _told.add(key)
        print(f"plclab: {message}; the Python path runs", file=sys.stderr)


def cache_dir() -> Path:
    return user_cache_dir("native")


def c_compiler() -> Optional[str]:
    cc = os.environ.get("CC")
    if cc and shutil.which(cc):
        return shutil.which(cc)
    for name in ("cc", "gcc", "clang"):
        found = shutil.which(name)
        if found:
            return found
    return None


PREFER_API = True
"""Build a CPython extension (cffi's API mode) where Python's headers are. The program's C is
the same either way; the semantics tests build plain libraries (ABI mode), a third of the
build time for their hundreds of small programs."""


def _key(cprog: CProgram, cc: str) -> tuple[str, bool, str, str]:
    """(module name, API mode?, Python include dir, file suffix) of a program's library."""
    include = sysconfig.get_paths().get("include") or ""
    api = PREFER_API and bool(include) and os.path.exists(os.path.join(include, "Python.h"))
    ext = (sysconfig.get_config_var("EXT_SUFFIX") or ".so") if api else ".so"
    key = hashlib.sha256("\0".join((cprog.source, cprog.cdef, cc, *CFLAGS, ext, include,
                                     f"api={api}")).encode()).hexdigest()[:32]
    return f"_plclab_native_{key}", api, include, ext


def build(cprog: CProgram, wait: bool = True, later: bool = True) -> Optional[tuple[Any, Any]]:
    """(ffi, lib) of a generated program: a CPython extension module (cffi's API mode: the
    fastest calls) where Python's headers are installed, else a plain shared library loaded
    through cffi's ABI mode; loaded from the cache, or compiled now. With `wait` False a
    library not built yet is None now, and built in a background thread if `later` (a
    later load finds it). None also without a compiler or when the build fails."""
    cc = c_compiler()
    if cc is None:
        _inform("cc", "no C compiler (cc) found for the native scan path")
        return None
    modname, api, include, ext = _key(cprog, cc)
    loaded = _LOADED.get(modname)
    if loaded is not None:
        return loaded
    out_dir = cache_dir()
    lib_path = out_dir / f"{modname}{ext}"
    if not lib_path.exists():
        if not wait:
            if later:
                _build_later(cprog, cc, api, include, modname, out_dir, lib_path)
            return None
        if modname in _BROKEN:
            return None
        with _BUILD_LOCK:
            if not lib_path.exists() and not _compile(cprog, cc, api, include, modname, out_dir, lib_path):
                _BROKEN.add(modname)         # tried once in this process: the Python path from now on
                return None
    try:
        loaded = _load(cprog, api, modname, lib_path)
        _mark_used(lib_path)
    except Exception as e:       # a damaged cache file (or one pruned meanwhile): built again once
        try:
            lib_path.unlink()
        except OSError:
            pass
        if not wait or not _compile(cprog, cc, api, include, modname, out_dir, lib_path):
            return None
        try:
            loaded = _load(cprog, api, modname, lib_path)
        except Exception:
            _inform("load", f"the native library did not load ({e})")
            return None
    _LOADED[modname] = loaded
    return loaded


_BUILD_LOCK = threading.Lock()      # one build at a time in this process
_STATE_LOCK = threading.Lock()
_BUILDING: set[str] = set()


def _after_fork_in_child() -> None:
    """A forked worker (grade-class) has no build thread of its parent: fresh locks, and the
    builds the parent started are looked for on disk again."""
    global _BUILD_LOCK, _STATE_LOCK
    _BUILD_LOCK, _STATE_LOCK = threading.Lock(), threading.Lock()
    _BUILDING.clear()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_after_fork_in_child)


def _build_later(cprog: CProgram, cc: str, api: bool, include: str, modname: str, out_dir: Path,
                 lib_path: Path) -> None:
    with _STATE_LOCK:
        if modname in _BUILDING:
            return
        _BUILDING.add(modname)

    def work() -> None:
        with _BUILD_LOCK:
            if not lib_path.exists():
                _compile(cprog, cc, api, include, modname, out_dir, lib_path)
    threading.Thread(target=work, name="plclab-native-build", daemon=True).start()


_LOADED: dict[str, tuple[Any, Any]] = {}
_BROKEN: set[str] = set()


def _compile(cprog: CProgram, cc: str, api: bool, include: str, modname: str, out_dir: Path,
             lib_path: Path) -> bool:
    import cffi
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        work = Path(tempfile.mkdtemp(prefix="build-", dir=out_dir))
    except OSError as e:
        _inform("cache", f"cannot write the native cache {out_dir}: {e.strerror}")
        return False
    try:
        src = work / f"{modname}.c"
        if api:
            from cffi.recompiler import make_c_source
            ffi = cffi.FFI()
            ffi.cdef(cprog.cdef)
            # what ffi.emit_c_code writes, without its "generating ..." line: a build may run in
            # a background thread, where redirecting sys.stdout to hush it would take the main
            # thread's output away too (seen: a command's report lost in the test suite)
            make_c_source(ffi, modname, cprog.source, str(src), verbose=False)
            extra = [f"-I{include}"]
        else:
            src.write_text(cprog.source)
            extra = []
        tmp_lib = work / lib_path.name
        r = subprocess.run([cc, *CFLAGS, *extra, "-o", str(tmp_lib), str(src), "-lm"], capture_output=True,
                           text=True, timeout=BUILD_TIMEOUT_S)
        if r.returncode != 0:
            first = (r.stderr.strip().splitlines() or ["?"])[0]
            _inform("build", f"the native build failed ({first})")
            return False
        os.replace(tmp_lib, lib_path)          # atomic: another process sees all of it or nothing
        prune(out_dir, keep=lib_path)
        return True
    except (OSError, subprocess.SubprocessError) as e:
        _inform("build", f"the native build failed ({e})")
        return False
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _mark_used(lib_path: Path) -> None:
    """A library's time is when it was last loaded: what pruning goes by."""
    try:
        os.utime(lib_path)
    except OSError:
        pass


def prune(out_dir: Path, keep: Optional[Path] = None) -> list[str]:
    """Bound the cache after a build: the libraries loaded least recently go until the rest
    take at most CACHE_MAX_BYTES, never `keep` (the one just built); the
    folders of builds that died long ago go too. Safe beside other processes: a library
    removed under another's load is built again there (build()). The names removed."""
    now = time.time()
    libs: list[tuple[float, int, str]] = []
    removed: list[str] = []
    try:
        with os.scandir(out_dir) as entries:
            for entry in entries:
                try:
                    st = entry.stat(follow_symlinks=False)
                    if entry.name.startswith("_plclab_native_") and entry.is_file(follow_symlinks=False):
                        libs.append((st.st_mtime, st.st_size, entry.name))
                    elif entry.name.startswith("build-") and entry.is_dir(follow_symlinks=False) \
                            and now - st.st_mtime > STALE_BUILD_S:
                        shutil.rmtree(entry.path, ignore_errors=True)
                        removed.append(entry.name)
                except OSError:
                    continue
    except OSError:
        return removed
    total = sum(size for _t, size, _n in libs)
    for _t, size, name in sorted(libs):
        if total <= CACHE_MAX_BYTES:
            break
        if keep is not None and name == keep.name:
            continue
        try:
            os.unlink(os.path.join(out_dir, name))
        except OSError:
            continue
        total -= size
        removed.append(name)
    return removed


def _load(cprog: CProgram, api: bool, modname: str, lib_path: Path) -> tuple[Any, Any]:
    if api:
        import importlib.machinery
        import importlib.util
        loader = importlib.machinery.ExtensionFileLoader(modname, str(lib_path))
        spec = importlib.util.spec_from_file_location(modname, str(lib_path), loader=loader)
        module = importlib.util.module_from_spec(spec)
        loader.exec_module(module)
        return module.ffi, module.lib
    import cffi
    ffi = cffi.FFI()
    ffi.cdef(cprog.cdef)
    return ffi, ffi.dlopen(str(lib_path))


def program_for(compiled: Any, wait: bool = False) -> Optional["NativeProgram"]:
    """The native program of a compiled (Python path) program, or None when native does not
    run it (now). A library is built once per program (its C's hash): with `wait`, now;
    else in the background from the second load of the same program on, so a program
    loaded once (a unit test, one `plclab sim`) costs no build, and one loaded again and
    again (grading, exploration, restarts) scans natively as soon as its build is done."""
    cached = getattr(compiled, "_native", None)
    if isinstance(cached, NativeProgram):
        return cached
    if cached is _FAILED:
        return None
    if isinstance(cached, CProgram):
        cprog = cached
    else:
        try:
            cprog = _emitted(compiled.checked)
        except Unsupported as e:
            _inform(f"unsupported:{e}", f"the native scan path does not cover {e}")
            _remember(compiled, _FAILED)
            return None
    digest = hashlib.sha256(cprog.source.encode()).hexdigest()
    _SEEN[digest] = _SEEN.get(digest, 0) + 1
    built = build(cprog, wait=wait, later=_SEEN[digest] >= 2)
    if built is None:
        _remember(compiled, cprog)       # not now; a later load may find the library built
        return None
    result = NativeProgram(cprog, *built)
    _remember(compiled, result)
    return result


_SEEN: dict[str, int] = {}
# id(checked unit) -> its C (or the Unsupported emit_c raised), while the unit lives
_EMITTED: dict[int, Any] = {}


def _emitted(checked: Any) -> CProgram:
    """emit_c(checked), once per checked unit: every session and restart of one program
    compiles it to Python anew (its own state), but its C, what keys the library, is the
    same (the front end gives the same CheckedUnit for the same files)."""
    key = id(checked)
    got = _EMITTED.get(key)
    if got is None:
        try:
            got = emit_c(checked)
        except Unsupported as e:
            got = e
        _EMITTED[key] = got
        weakref.finalize(checked, _EMITTED.pop, key, None)
    if isinstance(got, Unsupported):
        raise Unsupported(*got.args)      # a new one each time: a raised one keeps its frames
    return got


def _remember(compiled: Any, value: Any) -> None:
    try:
        compiled._native = value
    except AttributeError:
        pass


class NativeProgram:
    """A loaded native library and the mirror classes of its structs."""

    def __init__(self, cprog: CProgram, ffi: Any, lib: Any):
        self.cprog, self.ffi, self.lib = cprog, ffi, lib
        self._classes: dict[tuple[str, Any], type] = {}
        self._exposed: dict[tuple[str, type], tuple[frozenset[str], tuple[str, ...]]] = {}

    def attach(self, plc: Any) -> Any:
        """Fresh C state for `plc`: every variable takes the value the Python path just
        initialised it to (so initial values, FB initialisers and retain restore are the
        Python path's own), and the PLC's instances and globals become mirrors of it."""
        ffi, lib, cprog = self.ffi, self.lib, self.cprog
        st = ffi.new("State *")
        keep = [st]
        g = self.mirror(cprog.layouts["GLOBALS"], st.g, plc.compiled.namespace["G"], keep)
        keys = [type(inst.obj)._ST_NAME.upper() for inst in plc.instances]
        if keys != cprog.instances:      # pragma: no cover - cgen follows PLC._setup_instances
            raise RuntimeError(f"native instances {cprog.instances} are not the PLC's {keys}")
        for i, inst in enumerate(plc.instances):
            sname = cprog.program_structs[keys[i]]
            inst.obj = self.mirror(cprog.layouts[sname], getattr(st, f"inst{i}"), inst.obj, keep)
        plc._native_keep = keep
        plc._native_state = st
        return g

    def io(self, plc: Any, copy_in: Any, copy_out: Any) -> tuple[Any, Any]:
        """The image <-> variable copies of PLC._compile_io, converted in C: one call with the
        raw input values, one that fills a buffer with the raw output values. At the same
        stages of the scan as on the Python path, so what runs between them (the lab's
        forces) sees the same. The Python copy through the mirrors (`copy_in`) stays for the
        outputs read back after a client wrote them."""
        ffi, lib = self.ffi, self.lib
        ins, outs = self.cprog.io_bindings
        if [(b.area, b.index) for b in plc._inputs] != ins or [(b.area, b.index) for b in plc._outputs] != outs:
            raise RuntimeError("native I/O bindings are not the PLC's")   # pragma: no cover
        obuf = ffi.new("uint64_t[]", max(1, len(outs)))
        ns: dict[str, Any] = {"st": plc._native_state, "obuf": obuf, "io_in": lib.io_in, "io_out": lib.io_out,
                              "unpack": ffi.unpack, "slow_in": copy_in, "wrap": _wrap_raw}
        for area in {a for a, _i in ins + outs}:
            ns[f"a_{area}"] = plc.image.areas[area]       # the area lists are never replaced
        gather = "".join(f"a_{a}[{i}], " for a, i in ins)
        lines = ["def _copy_in(external):", "    try:", f"        io_in(st, {gather})",
                 "    except (OverflowError, TypeError):      # a raw value past 64 bits: its low 64 bits",
                 f"        io_in(st, *map(wrap, ({gather})))",
                 "    if external:", "        slow_in(external)",
                 "def _copy_out(areas):", "    io_out(st, obuf)"]
        if outs:
            lines.append(f"    v = unpack(obuf, {len(outs)})")
            for j, (a, i) in enumerate(outs):
                lines.append(f"    a_{a}[{i}] = v[{j}]")
        define("\n".join(lines) + "\n", "<plc-native-io>", ns)
        plc._native_obuf = obuf
        return ns["_copy_in"], ns["_copy_out"]

    def quiet(self, plc: Any) -> Callable[[int, Optional["Watch"]], tuple[int, int]]:
        """`run(n, watch) -> (scans, fault code)`: up to n scans in one C call with the inputs
        the image holds now, stopping after the first that changes an output or a `watch`ed
        variable, or faults (PLC.run_quiet says when that is the same as n scans)."""
        ffi, lib = self.ffi, self.lib
        ins = self.cprog.io_bindings[0]
        raw_in = ffi.new("int64_t[]", max(1, len(ins)))
        rc = ffi.new("int32_t *")
        cells = [(plc.image.areas[a], i) for a, i in ins]
        obuf, st, quiet = plc._native_obuf, plc._native_state, lib.scan_quiet
        nothing = Watch(ffi, [])

        def run(n: int, watch: Optional[Watch]) -> tuple[int, int]:
            raw = [area[i] for area, i in cells]
            try:
                raw_in[0:len(raw)] = raw
            except (OverflowError, TypeError):       # a raw value past 64 bits: its low 64 bits
                raw_in[0:len(raw)] = [_wrap_raw(x) for x in raw]
            w = watch or nothing
            k = quiet(st, plc.ticks, plc.tick_ns, plc.watchdog_s, plc._native_periods, n, raw_in, obuf,
                      w.ptrs, w.sizes, w.count, w.snap, rc)
            return k, rc[0]
        return run


    def schedule(self, plc: Any, sched: list) -> list:
        """PLC._make_schedule's list as one entry: one C call runs every instance whose
        period divides the tick, in declaration order."""
        fn, sites = self.lib.scan, self.cprog.sites
        periods = self.ffi.new("int64_t[]", [p for p, _r in sched] or [1])
        st = plc._native_state
        clock = plc.scan_clock

        def run_all() -> None:
            rc = fn(st, clock.now, plc.watchdog_s, plc.ticks, periods)
            if rc:
                raise _fault(rc, st, sites, plc)
        plc._native_periods = periods
        return [(1, run_all)]

    def mirror(self, layout: Layout, cdata: Any, pyobj: Any, keep: list) -> Any:
        """A mirror of the C struct `cdata`; its values copied from `pyobj` (None: a view of
        what the C holds, e.g. the variable a VAR_IN_OUT points at)."""
        cls = self._class(layout, type(pyobj) if pyobj is not None else T.StructValue, pyobj)
        proxy = cls.__new__(cls)
        _init_proxy(self, proxy, layout, cdata, pyobj, keep)
        return proxy

    def view(self, layout: Layout, cdata: Any) -> Any:
        return self.mirror(layout, cdata, None, [])

    def exposed(self, layout: Layout, pyobj: Any) -> tuple[frozenset[str], tuple[str, ...]]:
        """The variables a mirror of `layout` shows for a twin like `pyobj` (`_exposed`), and
        those of them it copies (all but VAR_IN_OUT references): worked out once per layout
        and twin type, as its mirror class is (`_class`). Every PLC of a program mirrors the
        same blocks anew, and an exploration starts thousands of PLCs."""
        key = (layout.cname, type(pyobj))
        got = self._exposed.get(key)
        if got is None:
            names = frozenset(_exposed(layout, pyobj))
            got = self._exposed[key] = (names, tuple(f.name for f in layout.fields
                                                     if f.name in names and f.kind != "ref"))
        return got

    def _class(self, layout: Layout, pytype: type, pyobj: Any) -> type:
        key = (layout.cname, pytype)
        cls = self._classes.get(key)
        if cls is None:
            cls = _make_class(self, layout, pytype, pyobj)
            self._classes[key] = cls
        return cls


class Watch:
    """C memory a quiet run compares after each scan (PLC.run_quiet): the variables named by
    (container, key) pairs as PLC.resolve gives them, and room for a copy of their bytes
    (taken by the run as it begins)."""

    def __init__(self, ffi: Any, places: list[tuple[Any, int]]):
        self.count = len(places)
        self.ptrs = ffi.new("char *[]", [ffi.cast("char *", p) for p, _n in places] or [ffi.NULL])
        self.sizes = ffi.new("int64_t[]", [n for _p, n in places] or [0])
        self.snap = ffi.new("char[]", max(1, sum(n for _p, n in places)))   # the C fills it
        self._keep = places

    @staticmethod
    def of(plc: Any, pairs: Sequence[tuple[Any, Any]]) -> Optional["Watch"]:
        """The watch of `pairs` on `plc`'s native memory; None where one of them is not a
        scalar in it (a Python path, a reference): then no quiet run can keep it."""
        np = plc.native
        if np is None:
            return None
        ffi = np.ffi
        places = []
        for o, k in pairs:
            if isinstance(o, ArrayMirror) and o._items is None and isinstance(k, int):
                places.append((ffi.addressof(o._a, k), ffi.sizeof(ffi.typeof(o._a).item)))
                continue
            f = getattr(type(o), "_fields", {}).get(k) if isinstance(k, str) else None
            if f is None or f.kind != "scalar" or not hasattr(o, "_p"):
                return None
            ptr = ffi.addressof(o._p[0] if ffi.typeof(o._p).kind == "pointer" else o._p, f.cname)
            places.append((ptr, ffi.sizeof(ffi.typeof(ptr).item)))
        return Watch(ffi, places)


class RetainMemory:
    """The retained variables of a native PLC as memory: called, the bytes (and elementary
    values) that are equal only where they hold equal values; `put_back` makes them hold
    what such a call gave."""

    def __init__(self, parts: list[Any]):
        self.parts = parts            # a C buffer, or (owner, attribute) of an elementary one

    def __call__(self) -> tuple:
        return tuple(p[:] if not isinstance(p, tuple) else getattr(*p) for p in self.parts)

    def put_back(self, fingerprint: tuple) -> None:
        for p, v in zip(self.parts, fingerprint):
            if isinstance(p, tuple):
                setattr(p[0], p[1], v)
            else:
                p[:] = v


def retain_fingerprint(plc: Any) -> Any:
    """A RetainMemory of the retained variables of `plc` (a native PLC): the C memory of each
    (an FB instance, a structure or an array with no VAR_IN_OUT pointer inside, whose target
    could change unseen) or the value of an elementary one; a function giving None where one
    of them is none of these."""
    np = plc.native
    buffer = np.ffi.buffer
    parts: list[Any] = []
    for _path, owner, attr, _ty in plc.retained():
        value = getattr(owner, attr)
        memory = _memory_of(np, value)
        if memory is not None:
            if np.ffi.typeof(memory).kind not in ("pointer", "array"):
                memory = np.ffi.addressof(memory)        # a struct member: where it lies
            parts.append(buffer(memory))
        elif isinstance(value, (bool, int, float, str)):
            parts.append((owner, attr))
        else:
            return lambda: None
    return RetainMemory(parts)


def _memory_of(np: NativeProgram, value: Any) -> Any:
    """The C memory holding all of `value` (a mirror or an ArrayMirror), or None where it
    reaches through a pointer or is no mirror."""
    if isinstance(value, ArrayMirror):
        items = value._items                 # an array's elements are all of one layout
        return value._a if not items or _pointer_free(np, type(items[0])) else None
    if getattr(value, "_p", None) is not None and _pointer_free(np, type(value)):
        return value._p
    return None


def _pointer_free(np: NativeProgram, cls: type) -> bool:
    fields = getattr(cls, "_fields", None)
    if fields is None:
        return False
    seen: set[str] = set()
    todo = list(fields.values())
    while todo:
        f = todo.pop()
        if f.kind == "ref":
            return False
        if f.sub is not None and f.sub not in seen and (f.kind in ("struct", "fb") or f.sub_kind != "scalar"):
            seen.add(f.sub)
            todo.extend(np.cprog.layouts[f.sub].fields)
    return True


def _wrap_raw(x: int) -> int:
    """A raw image value as the C reads it: its low 64 bits (the conversions mask it)."""
    x = int(x) & 0xFFFFFFFFFFFFFFFF
    return x - (1 << 64) if x >> 63 else x


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


def _exposed(layout: Layout, pyobj: Any) -> list[str]:
    """The variables a mirror shows: those its Python twin has (all, for a view)."""
    return [f.name for f in layout.fields if pyobj is None or hasattr(pyobj, f.name)]


def _make_class(np: "NativeProgram", layout: Layout, pytype: type, pyobj: Any) -> type:
    names = _exposed(layout, pyobj)
    lines = []
    for f in layout.fields:
        if f.name not in names:
            continue
        if f.kind == "scalar":
            lines += [f"    @property\n    def {f.name}(self): return self._p.{f.cname}",
                      f"    @{f.name}.setter\n    def {f.name}(self, v): self._p.{f.cname} = v"]
        elif f.kind == "ref":         # a VAR_IN_OUT: what the last call passed (None before)
            lines += [f"    @property\n    def {f.name}(self): return _ref(self, {f.name!r})"]
        else:
            lines += [f"    @property\n    def {f.name}(self): return self._k['{f.name}']",
                      f"    @{f.name}.setter\n    def {f.name}(self, v): _assign(self._k['{f.name}'], v)"]
    is_struct = layout.kind == "struct"
    base = "StructMirror" if is_struct else "object"
    slots = "()" if is_struct else "('_p', '_k', '_names', '__weakref__')"
    src = f"class Mirror({base}):\n    __slots__ = {slots}\n" + "\n".join(lines) + "\n"
    if not is_struct:
        src += "    def __call__(self):\n        raise TypeError('a native block is called by the C code')\n"
    ns: dict[str, Any] = {"StructMirror": StructMirror, "_assign": _assign, "_ref": _ref}
    define(src, f"<plc-native-{layout.cname}>", ns)
    cls = ns["Mirror"]
    cls.__name__ = cls.__qualname__ = getattr(pytype, "__name__", layout.cname)
    cls._np = np
    cls._fields = {f.name: f for f in layout.fields}
    if not is_struct:
        # what the runtime reads of a program / block class: its variables and ST name
        cls.__slots__ = getattr(pytype, "__slots__", tuple(n for n in names if n not in ("EN", "ENO")))
        cls._ST_NAME = getattr(pytype, "_ST_NAME", layout.st_name)
    return cls


class ScalarRef:
    """A scalar VAR_IN_OUT as the Python path shows it (compiler.Ref): get() / set()."""

    __slots__ = ("_ptr",)

    def __init__(self, ptr: Any):
        self._ptr = ptr

    def get(self) -> Any:
        return self._ptr[0]

    def set(self, value: Any) -> None:
        self._ptr[0] = value


def _ref(obj: Any, name: str) -> Any:
    cls = type(obj)
    f, np = cls._fields[name], cls._np
    ptr = getattr(obj._p, f.cname)
    if ptr == np.ffi.NULL:
        return None
    if isinstance(f.ty, T.ArrayType):
        m = ArrayMirror()
        m._a, m._n = np.ffi.cast(f"{f.sub}(*)[{f.ty.size}]", ptr)[0], f.ty.size   # an array, not a pointer
        sub = np.cprog.layouts.get(f.sub)
        m._items = None if sub is None else [np.view(sub, ptr[i]) for i in range(m._n)]
        return m
    if isinstance(f.ty, T.StructType):
        return np.view(np.cprog.layouts[f.sub], ptr[0])
    return ScalarRef(ptr)


def _init_proxy(np: NativeProgram, proxy: Any, layout: Layout, cdata: Any, pyobj: Any, keep: list) -> None:
    """Point `proxy` at `cdata`; with a Python twin `pyobj`, copy its values into the C."""
    names, proxy._names = np.exposed(layout, pyobj)
    proxy._p = cdata
    kids: dict[str, Any] = {}
    proxy._k = kids
    for f in layout.fields:
        if f.name not in names or f.kind == "ref":
            continue
        value = getattr(pyobj, f.name) if pyobj is not None else None
        if f.kind == "scalar":
            if pyobj is not None:
                setattr(cdata, f.cname, value)
        elif f.kind in ("struct", "fb"):
            kids[f.name] = np.mirror(np.cprog.layouts[f.sub], getattr(cdata, f.cname), value, keep)
        elif f.kind == "array":
            arr = getattr(cdata, f.cname)
            m = ArrayMirror()
            m._a, m._n = arr, f.size
            if f.sub_kind == "scalar":
                m._items = None
                if pyobj is not None:
                    arr[0:f.size] = list(value)
            else:
                sub = np.cprog.layouts[f.sub]
                m._items = [np.mirror(sub, arr[i], value[i] if value is not None else None, keep)
                            for i in range(f.size)]
            kids[f.name] = m


__all__ = ["ENV", "NativeProgram", "build", "cache_dir", "program_for", "prune", "python_only", "setting", "wanted"]
