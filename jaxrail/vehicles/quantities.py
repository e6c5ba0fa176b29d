"""Numbers of a vehicle file: quantity tables, named parameters and expressions.

A number in a vehicle file is one of

- a **quantity table** ``{ value = 1.22, unit = "MN/m", source = "...", tag = "V-src" }``;
  ``value`` may be a list (one unit for every entry, or a list of units, one per entry
  of a vector or one per column of a table of rows);
- an **expression** of named parameters, a string such as ``"a + b"`` or
  ``"-carbody.bogie_half_distance"``: numbers, names (dotted for a parameter in a
  group), ``+ - * /``, unary minus and parentheses, nothing else (evaluated on
  Python's ``ast``, never ``eval``). Its dimension follows from its parameters;
- ``0``, which is zero in every unit (as is a zero entry of a quantity table); or, where a field is a direction (``axis*``,
  ``frame*``), plain numbers.

Everything is converted to SI on reading (:mod:`jaxrail.vehicles.units`); a value is a
:class:`Quantity` (a float and its dimension). Errors are ``ValueError``s that name
the file, the table and the key (:func:`file_error`).
"""

import ast
import operator
from typing import NamedTuple

from .units import Dimension, describe, parse_unit, to_si

TAGS = ("V-src", "R", "A")
QUANTITY_KEYS = {"value", "unit", "source", "tag"}
ANY: None = None  # the dimension of a bare 0, which fits every unit


def file_error(where: str, table: str, key: str, problem: str) -> ValueError:
    """The error for ``problem`` at ``key`` of ``table`` in the file ``where``."""
    return ValueError(f"{where}: [{table}] {key}: {problem}")


class Quantity(NamedTuple):
    """A number in SI units and its dimension (powers of kg, m, s; None for a bare 0)."""

    value: float
    dimension: Dimension | None


_BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
           ast.Div: operator.truediv}


def _dotted(node) -> str:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return f"{_dotted(node.value)}.{node.attr}"
    raise ValueError("only numbers, parameter names, + - * /, unary minus and parentheses "
                     "are allowed")


def _combine(op, a: Quantity, b: Quantity, text: str) -> Quantity:
    if op in (ast.Add, ast.Sub):
        if ANY not in (a.dimension, b.dimension) and a.dimension != b.dimension:
            raise ValueError(f"{text!r} adds {describe(a.dimension)} to "
                             f"{describe(b.dimension)}")
        dim = b.dimension if a.dimension is ANY else a.dimension
    else:
        da, db = a.dimension or (0, 0, 0), b.dimension or (0, 0, 0)
        sign = 1 if op is ast.Mult else -1
        dim = tuple(x + sign * y for x, y in zip(da, db))
    if op is ast.Div and b.value == 0.0:
        raise ValueError(f"{text!r} divides by zero")
    return Quantity(_BINARY[op](a.value, b.value), dim)


def evaluate(text: str, lookup) -> Quantity:
    """The :class:`Quantity` of the expression ``text``; ``lookup(name)`` gives a
    parameter's. ValueError for anything but the allowed syntax."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError:
        raise ValueError(f"{text!r} is not an expression") from None

    def scalar(node) -> Quantity:
        q = walk(node)
        if isinstance(q, list):
            raise ValueError(f"{text!r}: {ast.unparse(node)!r} is a vector; arithmetic "
                             f"takes single numbers (a vector parameter stands alone)")
        return q

    def walk(node) -> Quantity:
        if isinstance(node, ast.Constant) and type(node.value) in (int, float):
            return Quantity(float(node.value), (0, 0, 0))
        if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
            return _combine(type(node.op), scalar(node.left), scalar(node.right), text)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            q = scalar(node.operand)
            return Quantity(-q.value if isinstance(node.op, ast.USub) else q.value,
                            q.dimension)
        if isinstance(node, (ast.Name, ast.Attribute)):
            return lookup(_dotted(node))
        raise ValueError(f"{text!r}: only numbers, parameter names, + - * /, unary minus "
                         f"and parentheses are allowed")

    return walk(tree.body)


def _convert(value, unit, text):
    """Nested lists of Quantity from a quantity table's value and unit(s)."""
    if isinstance(unit, list):
        if not isinstance(value, list) or len(unit) == 0:
            raise ValueError(f"a list of units needs a list value, got {value!r}")
        rows = value if isinstance(value[0], list) else None
        width = len(rows[0]) if rows else len(value)
        if len(unit) != width:
            raise ValueError(f"{len(unit)} units for {width} entries per "
                             f"{'row' if rows else 'vector'}")
        units = [parse_unit(u) for u in unit]
        if rows:
            if any(not isinstance(r, list) or len(r) != width for r in rows):
                raise ValueError(f"every row must have {width} entries")
            return [[_number(v, u, text) for v, u in zip(r, units)] for r in rows]
        return [_number(v, u, text) for v, u in zip(value, units)]
    parsed = parse_unit(unit)

    def each(v):
        return [each(x) for x in v] if isinstance(v, list) else _number(v, parsed, text)

    return each(value)


def _number(v, unit, text) -> Quantity:
    if type(v) not in (int, float):
        raise ValueError(f"value entries must be numbers, got {v!r}")
    # zero is zero in every unit: [160, 160, 430, 0, 0, 0] kN/m fits a bushing's six
    return Quantity(to_si(v, unit), unit.dimension if v != 0 else ANY)


def quantity_table(entry: dict):
    """Quantity (or nested lists of them) of a ``{value, unit, source, tag}`` table;
    ValueError (without the location) for a missing or unknown key, unit or tag."""
    keys = set(entry)
    if keys != QUANTITY_KEYS:
        missing = sorted(QUANTITY_KEYS - keys)
        extra = sorted(keys - QUANTITY_KEYS)
        raise ValueError("a number needs exactly value, unit, source and tag"
                         + (f"; missing {', '.join(missing)}" if missing else "")
                         + (f"; unknown {', '.join(extra)}" if extra else ""))
    if entry["tag"] not in TAGS:
        raise ValueError(f"tag {entry['tag']!r} is not one of {', '.join(TAGS)}")
    if not isinstance(entry["source"], str) or not entry["source"].strip():
        raise ValueError("source must be a non-empty string")
    return _convert(entry["value"], entry["unit"], str(entry))


class Parameters:
    """The named parameters of a file (``[parameters]``, groups as sub-tables), each a
    quantity table or an expression of others, evaluated on first use (cycles are
    errors). ``overrides``: ``{"group.name": value in SI}`` replacing file values.

    ``entries``: ``{name: (raw entry, table, key)}``; ``provenance(name)`` gives the
    raw quantity table (value, unit, source, tag) of a file value."""

    def __init__(self, raw: dict, where: str, overrides=None):
        self.where, self.entries, self._cache, self._busy = where, {}, {}, set()
        self._collect(raw, "")
        for name, value in (overrides or {}).items():
            if name not in self.entries:
                raise ValueError(f"{where}: unknown parameter {name!r} to override; "
                                 f"known: {', '.join(sorted(self.entries))}")
            q = self.get(name)
            if isinstance(q, list) or type(value) not in (int, float):
                raise ValueError(f"{where}: parameter {name!r}: overrides take one float "
                                 f"(in SI units), got {value!r}")
            self._cache[name] = Quantity(float(value), q.dimension)

    def _collect(self, raw, prefix):
        table = "parameters" + (f".{prefix[:-1]}" if prefix else "")
        if not isinstance(raw, dict):
            raise file_error(self.where, table, "", "must be a table")
        for key, entry in raw.items():
            if not key.isidentifier():
                raise file_error(self.where, table, key, "parameter names must be "
                                 "identifiers (letters, digits, _)")
            if isinstance(entry, dict) and "value" not in entry:
                self._collect(entry, f"{prefix}{key}.")
            else:
                self.entries[prefix + key] = (entry, table, key)

    def get(self, name: str):
        """The Quantity of the parameter ``name``; ValueError if there is none."""
        if name in self._cache:
            return self._cache[name]
        if name not in self.entries:
            known = ", ".join(sorted(self.entries)) or "none"
            raise ValueError(f"unknown parameter {name!r} (parameters: {known})")
        entry, table, key = self.entries[name]
        if name in self._busy:
            raise file_error(self.where, table, key, "the parameter depends on itself")
        self._busy.add(name)
        try:
            if isinstance(entry, str):
                value = evaluate(entry, self.get)
            elif isinstance(entry, dict):
                value = quantity_table(entry)
            else:
                raise ValueError("a parameter is a {value, unit, source, tag} table or an "
                                 "expression string")
        except ValueError as error:
            if str(error).startswith(self.where):
                raise
            raise file_error(self.where, table, key, str(error)) from None
        finally:
            self._busy.discard(name)
        self._cache[name] = value
        return value

    def provenance(self, name: str) -> dict | None:
        """The file's ``{value, unit, source, tag}`` of a parameter (None for an
        expression)."""
        entry = self.entries[name][0]
        return entry if isinstance(entry, dict) else None


def read_number(entry, parameters: Parameters, plain_numbers: bool = False):
    """A field's value as a Quantity or nested lists of them: a quantity table, an
    expression, 0, a list of these, or (``plain_numbers``, for directions) bare numbers
    as dimensionless. ValueError (without the location) otherwise."""
    if isinstance(entry, bool):
        raise ValueError(f"expected a number with its unit, got {entry!r}")
    if isinstance(entry, dict):
        return quantity_table(entry)
    if isinstance(entry, str):
        return evaluate(entry, parameters.get)
    if isinstance(entry, list):
        return [read_number(e, parameters, plain_numbers) for e in entry]
    if type(entry) in (int, float):
        if plain_numbers:
            return Quantity(float(entry), (0, 0, 0))
        if entry == 0:
            return Quantity(0.0, ANY)
        raise ValueError(f"the number {entry!r} has no unit: write "
                         f"{{ value = {entry!r}, unit = ..., source = ..., tag = ... }} "
                         f"or an expression of named parameters")
    raise ValueError(f"expected a number with its unit, got {entry!r}")


def check_dimension(q, expected, what: str = "") -> None:
    """ValueError if a Quantity (or nested lists) does not have the dimension of the
    unit ``expected`` (a unit string, a list of them per entry, or None: anything)."""
    if expected is None:
        return
    if isinstance(expected, list):
        if not isinstance(q, list) or len(q) != len(expected):
            raise ValueError(f"expected {len(expected)} entries, got "
                             f"{len(q) if isinstance(q, list) else 'one number'}")
        for k, (x, e) in enumerate(zip(q, expected)):
            check_dimension(x, e, f" (entry {k})")
        return
    if isinstance(q, list):
        for x in q:
            check_dimension(x, expected, what)
        return
    want = parse_unit(expected).dimension
    if q.dimension is not ANY and q.dimension != want:
        raise ValueError(f"the value{what} is a {describe(q.dimension)}, but this key "
                         f"needs a {describe(want)}")


def plain(q):
    """Floats (nested lists) of a Quantity (nested lists)."""
    return [plain(x) for x in q] if isinstance(q, list) else q.value
