"""A process memory limit for running a student's program: untrusted input is bounded in memory,
never more than its own FAIL.

The checker already bounds what a program may declare (plclab.frontend.check_limits,
MAX_DATA_BYTES); this is the second wall, for what no check foresaw. While a command runs a
student's program (`plclab grade`, `sim`, `run --program`; a grade-class or lab child for the
whole child), the process may grow by at most MEMORY_LIMIT_BYTES of address space beyond what it
used when the run started (RLIMIT_AS): a runaway ends in a MemoryError that the command reports
as one line (a scan that runs out is a PLC fault, `out_of_memory`), never in the machine
swapping. docs/reliability.md lists the limit.

    from plclab.limits import memory_limited, limit_memory, out_of_memory_message
    with memory_limited():                # a command in this process: the limit is lifted after
        run_the_program()
    limit_memory()                        # a child that only runs the program: for its whole life
    ...
    except MemoryError:
        print(out_of_memory_message("grade"))

Measured from the current size, the limit works the same in a fresh process and in a long-lived
one (a test session calling `plclab.cli.main`, the lab server).
"""
from __future__ import annotations

import os
from contextlib import contextmanager
from typing import Iterator, Optional

MEMORY_LIMIT_BYTES = 1024 * 1024 * 1024
"""1 GiB more than at the start of the run: PLC Lab grading a program takes about 100 MiB in all
(250 MiB when it plots); a program at the checker's 4 MiB of declared data stays far below."""
ENV_VAR = "PLCLAB_MEMORY_LIMIT_MB"
"""Overrides MEMORY_LIMIT_BYTES, in MiB (a smaller machine, a test); 0 turns the limit off."""


def memory_allowance() -> Optional[int]:
    """How many bytes a run may grow by (the environment may override it), or None when the
    limit is turned off."""
    text = os.environ.get(ENV_VAR, "").strip()
    if not text:
        return MEMORY_LIMIT_BYTES
    try:
        mb = int(text)
    except ValueError:
        return MEMORY_LIMIT_BYTES          # a typo never lifts the limit
    return mb * 1024 * 1024 if mb > 0 else None


def _address_space_now() -> int:
    """The process's current address space in bytes (0 where /proc cannot tell)."""
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("VmSize:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return 0


def _set_limit(allowance: Optional[int]) -> Optional[tuple[int, int]]:
    """Lower RLIMIT_AS's soft limit to the current size plus `allowance`; the previous
    (soft, hard) pair to restore, or None when nothing was changed."""
    if allowance is None:
        return None
    try:
        import resource
    except ImportError:                    # pragma: no cover - not on the lab's Linux machines
        return None
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = _address_space_now() + allowance
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    if soft != resource.RLIM_INFINITY and soft <= limit:
        return None                        # already as low or lower: keep it
    try:
        resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    except (ValueError, OSError):          # pragma: no cover - a platform that refuses it
        return None
    return soft, hard


def limit_memory(allowance: Optional[int] = -1) -> bool:
    """Hold this process (and the children it starts later) to its current size plus
    `allowance` bytes (default memory_allowance()) for the rest of its life: for a child
    process that runs a student's program. True if a limit was set."""
    return _set_limit(memory_allowance() if allowance == -1 else allowance) is not None


@contextmanager
def memory_limited(allowance: Optional[int] = -1) -> Iterator[None]:
    """Run the body with the process held to its current size plus `allowance` bytes (default
    memory_allowance()); the previous limit is restored after."""
    previous = _set_limit(memory_allowance() if allowance == -1 else allowance)
    try:
        yield
    finally:
        if previous is not None:
            import resource
            resource.setrlimit(resource.RLIMIT_AS, previous)


AT_LIMIT = 16 * 1024 * 1024      # bytes: a process that came this close to its memory limit reached it


def at_memory_limit() -> bool:
    """This process's peak address space came within AT_LIMIT of its RLIMIT_AS: an error it
    raised is most likely a failed allocation (C code reports one as a SystemError, or as any
    error of its own; Python's compiler as the MemoryError its parser also raises for code
    nested too deeply), not a bug of the grader or a fault of the program's text."""
    try:
        import resource
    except ImportError:                    # pragma: no cover - not on the lab's Linux machines
        return False
    soft, _hard = resource.getrlimit(resource.RLIMIT_AS)
    if soft == resource.RLIM_INFINITY:
        return False
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            peak = next(int(line.split()[1]) * 1024 for line in f if line.startswith("VmPeak:"))
    except MemoryError:                    # even reading the file failed to allocate: at the limit
        return True
    except (OSError, ValueError, IndexError, StopIteration):
        return False
    return peak >= soft - AT_LIMIT


def out_of_memory_message(what: str) -> str:
    """The one line a command prints when its run ran out of the memory limit."""
    allowance = memory_allowance()
    size = f"the {allowance // (1024 * 1024)} MiB" if allowance else "the machine's"
    return (f"{what}: out of memory: the run needed more than {size} memory limit of a program run "
            f"(docs/reliability.md); nothing else was affected")
