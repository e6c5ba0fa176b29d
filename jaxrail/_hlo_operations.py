"""The operations of a compiled program, counted in XLA's optimised HLO.

On the CPU, since jax 0.4.32, XLA runs a program as a sequence of thunks: one per
fused kernel and one per operation it does not fuse (a custom call such as a LAPACK
solve, a copy, a ``while`` or ``conditional``, a dot). Each has a fixed cost of a
fraction of a microsecond, so for small programs their number, not their flops, sets
the run time. :func:`operation_counts` counts the instructions of the optimised module
that become thunks: those of every computation except the bodies of fusions, less the
ones that produce no work (parameters, constants, tuples, their elements, bitcasts).
It is a static count: the body of an inner loop counts once, however many times it
runs.
"""

import collections
import re

_NO_WORK = frozenset({"parameter", "constant", "get-tuple-element", "tuple", "bitcast",
                      "after-all", "partition-id", "replica-id"})
_INSTRUCTION = re.compile(
    r"^\s*(?:ROOT\s+)?%?[\w.\-]+\s*=\s*(?:\([^=]*?\)|\S+)\s+([a-z][\w\-]*)\(")
_FUSED = re.compile(r"\bcalls=%?([\w.\-]+)")


def _computations(hlo_text: str) -> dict[str, list[tuple[str, str]]]:
    """{computation name: [(opcode, line), ...]} of an HLO module's text."""
    computations, current = {}, None
    for line in hlo_text.splitlines():
        stripped = line.strip()
        if stripped.endswith("{") and "->" in stripped and " = " not in stripped:
            name = stripped.removeprefix("ENTRY").strip().split()[0].lstrip("%")
            current = computations.setdefault(name, [])
            continue
        match = _INSTRUCTION.match(line)
        if match and current is not None:
            current.append((match.group(1), line))
    return computations


def operation_counts(compiled) -> dict:
    """``{"operations": n, "by_kind": {opcode: n}}`` of a compiled JAX program
    (``jax.jit(f).lower(...).compile()``), the operations that become thunks (module
    docstring)."""
    computations = _computations(compiled.as_text())
    fused = {m.group(1) for instructions in computations.values()
             for opcode, line in instructions if opcode == "fusion"
             for m in [_FUSED.search(line)] if m}
    kinds = collections.Counter(opcode for name, instructions in computations.items()
                                if name not in fused for opcode, _ in instructions
                                if opcode not in _NO_WORK)
    return {"operations": sum(kinds.values()), "by_kind": dict(kinds.most_common())}
