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

:func:`element_counts` counts the work inside those kernels: the elements each
instruction of the optimised module writes, fused or not, split into arithmetic
(everything that computes a new value) and data movement (copies, transposes,
concatenations, broadcasts, slices, gathers and the like, which only place values),
the moves inside a fused kernel that only remap its indices counted apart.
:func:`arithmetic_by_source` splits the arithmetic by the function that traced it
(the stack frames XLA keeps in each instruction's metadata).
"""

import collections
import math
import pathlib
import re

_NO_WORK = frozenset({"parameter", "constant", "get-tuple-element", "tuple", "bitcast",
                      "after-all", "partition-id", "replica-id"})
_INSTRUCTION = re.compile(
    r"^\s*(?:ROOT\s+)?%?[\w.\-]+\s*=\s*(?:\([^=]*?\)|\S+)\s+([a-z][\w\-]*)\(")
_FUSED = re.compile(r"\bcalls=%?([\w.\-]+)")
_RESULT = re.compile(r"=\s*(\([^=]*?\)|\S+)\s+[a-z][\w\-]*\(")
_ARRAY = re.compile(r"\b[a-z]+\d*\[([\d,]*)\]")
_NAMED = re.compile(r"^\s*(?:ROOT\s+)?%?([\w.\-]+)\s*=")
_OPERANDS = re.compile(r"%([\w.\-]+)")
_APPLIED = re.compile(r"\bto_apply=%?([\w.\-]+)")
_CONTRACTED = re.compile(r"lhs_contracting_dims=\{([\d,]*)\}")
# opcodes that place values without computing new ones
DATA_MOVEMENT = frozenset({"broadcast", "concatenate", "copy", "dynamic-slice",
                           "dynamic-update-slice", "gather", "iota", "pad", "reshape",
                           "reverse", "scatter", "slice", "transpose"})
# opcodes that write no elements of their own (calls, loops, fusions: their bodies count)
_CONTAINERS = _NO_WORK | {"fusion", "while", "conditional", "call", "custom-call"}


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


def _called(computations, opcode, reference) -> set[str]:
    """Names of the computations that instructions (of ``opcode``, or any) name by
    ``reference`` (a pattern such as ``calls=%name``)."""
    return {m.group(1) for instructions in computations.values()
            for kind, line in instructions if opcode in (None, kind)
            for m in [reference.search(line)] if m}


def operation_counts(compiled) -> dict:
    """``{"operations": n, "by_kind": {opcode: n}}`` of a compiled JAX program
    (``jax.jit(f).lower(...).compile()``), the operations that become thunks (module
    docstring)."""
    computations = _computations(compiled.as_text())
    fused = _called(computations, "fusion", _FUSED)
    kinds = collections.Counter(opcode for name, instructions in computations.items()
                                if name not in fused for opcode, _ in instructions
                                if opcode not in _NO_WORK)
    return {"operations": sum(kinds.values()), "by_kind": dict(kinds.most_common())}


def _shapes(text: str) -> list[list[int]]:
    """The dimensions of each array in a result type (one, or a tuple's)."""
    return [[int(d) for d in filter(None, dims.split(","))] for dims in _ARRAY.findall(text)]


def _elements(computations):
    """``(computation, opcode, line, written)`` of every instruction of an HLO module's
    ``computations`` (:func:`_computations`) that writes elements of its own (not in
    the reducers of reductions): the elements it writes, a reduction the elements it
    reads, a dot its multiply-adds."""
    reducers = _called(computations, None, _APPLIED)
    dims = {}  # instruction name -> its result's first array's dimensions
    for instructions in computations.values():
        for _, line in instructions:
            name, result = _NAMED.match(line), _RESULT.search(line)
            if name and result:
                shapes = _shapes(result.group(1))
                dims[name.group(1)] = shapes[0] if shapes else []
    for computation, instructions in computations.items():
        if computation in reducers:
            continue
        for opcode, line in instructions:
            if opcode in _CONTAINERS:
                continue
            result = _RESULT.search(line)
            written = sum(math.prod(d) for d in _shapes(result.group(1))) if result else 0
            operands = _OPERANDS.findall(line.split(opcode + "(", 1)[1])
            if opcode in ("reduce", "reduce-window") and operands:
                written = max(written, math.prod(dims.get(operands[0], [])))
            elif opcode == "dot" and operands:
                contracted = _CONTRACTED.search(line)
                lhs = dims.get(operands[0], [])
                axes = [int(a) for a in contracted.group(1).split(",") if a] if contracted else []
                written *= math.prod(lhs[a] for a in axes if a < len(lhs))
            yield computation, opcode, line, written


def element_counts(compiled) -> dict:
    """``{"arithmetic": n, "data_movement": n, "remapped_in_fusions": n, "by_kind":
    {opcode: n}}``: the element operations of a compiled JAX program's optimised HLO,
    inside fused kernels too (module docstring): the elements each instruction writes,
    a reduction the elements it reads, a dot its multiply-adds; a loop's body counts
    once. ``data_movement`` counts the moves that write memory: unfused ones and those
    a fused kernel writes out (its root); inside a kernel a broadcast, slice or
    transpose that feeds its arithmetic only changes indices (``remapped_in_fusions``).
    The reducers of reductions are part of those, and custom calls (LAPACK) are not
    counted: their work is not in the HLO."""
    computations = _computations(compiled.as_text())
    fused = _called(computations, "fusion", _FUSED)
    written_out = set()  # a fused kernel's outputs: its root, or its root tuple's parts
    for instructions in computations.values():
        for opcode, line in instructions:
            if line.lstrip().startswith("ROOT"):
                written_out.add(_NAMED.match(line).group(1))
                if opcode == "tuple":
                    written_out.update(_OPERANDS.findall(line.split("tuple(", 1)[1]))
    kinds, moved, remapped = collections.Counter(), 0, 0
    for computation, opcode, line, written in _elements(computations):
        kinds[opcode] += written
        if opcode in DATA_MOVEMENT:
            if computation in fused and _NAMED.match(line).group(1) not in written_out:
                remapped += written
            else:
                moved += written
    arithmetic = sum(n for kind, n in kinds.items() if kind not in DATA_MOVEMENT)
    return {"arithmetic": arithmetic, "data_movement": moved, "remapped_in_fusions": remapped,
            "by_kind": dict(kinds.most_common())}


def _frame_tables(hlo_text: str):
    """(files, functions, locations, frames) of an HLO module's text: the tables its
    instructions' ``stack_frame_id`` refers to (ids as strings)."""
    files, _, rest = hlo_text.partition("FunctionNames")
    functions, _, rest = rest.partition("FileLocations")
    named = re.compile(r'^(\d+) "([^"]*)"$', re.M)
    locations = {i: (f, fn, line) for i, f, fn, line in re.findall(
        r"^(\d+) \{file_name_id=(\d+) function_name_id=(\d+) line=(\d+)", rest, re.M)}
    frames = {i: (loc, parent) for i, loc, parent in re.findall(
        r"^(\d+) \{file_location_id=(\d+) parent_frame_id=(\d+)", rest, re.M)}
    return dict(named.findall(files)), dict(named.findall(functions)), locations, frames


_FRAME = re.compile(r"stack_frame_id=(\d+)")


def arithmetic_by_source(compiled, root=None) -> dict:
    """``{"file:function": n}``, most first: the arithmetic element operations of a
    compiled JAX program (as :func:`element_counts` counts them) by the innermost frame
    of each instruction's stack inside the directory ``root`` (default the jaxrail
    package), the file relative to it; ``"unattributed"`` where an instruction has no
    such frame (XLA drops the metadata of some instructions it rewrites, such as
    dots)."""
    root = str(root or pathlib.Path(__file__).resolve().parent).rstrip("/") + "/"
    text = compiled.as_text()
    files, functions, locations, frames = _frame_tables(text)

    def source(frame):
        for _ in range(len(frames)):  # a parent chain ends at a frame of its own
            if frame not in frames:
                break
            location, parent = frames[frame]
            file, function, _ = locations[location]
            if files[file].startswith(root):
                return f"{files[file][len(root):]}:{functions[function]}"
            if parent == frame:
                break
            frame = parent
        return "unattributed"

    counts = collections.Counter()
    for _, opcode, line, written in _elements(_computations(text)):
        if opcode not in DATA_MOVEMENT:
            frame = _FRAME.search(line)
            counts[source(frame.group(1)) if frame else "unattributed"] += written
    return dict(counts.most_common())
