"""The simulated time, reported from inside a compiled run to the host.

A run is one compiled program: diffrax's whole integration loop runs in XLA. To draw a
progress bar without cutting the run into pieces (which would restart the step-size
controller and change the answer), the loop reports its time through an XLA FFI
target, ``jaxrail_simulated_time``, registered here for the CPU. Its handler is a
small Python function behind a C function pointer (``ctypes``): XLA calls it with the
time as a float64 buffer, it hands the value to whatever :func:`listening` installed,
and returns. Unlike ``jax.debug.callback`` the program refers to the target by name
only, so JAX's persistent compilation cache keeps it and a later process that
imports jaxrail (which registers the target again) runs it from the cache.

The report has no output and changes no value: a program with it computes exactly
what it would without it. Runs make it through diffrax's progress-meter hook
(:class:`TimeReportingMeter`, after each step that enters a new thousandth of the
run); :func:`jaxrail.simulate` puts it in every run's program, with or without a bar,
so both are one program. On other backends (no target there)
:func:`report_time` adds nothing.
"""

import contextlib
import ctypes
import math
import threading
import time

import diffrax
import jax
import jax.numpy as jnp

TARGET = "jaxrail_simulated_time"

_EXECUTE = 3  # XLA_FFI_ExecutionStage_EXECUTE
_METADATA = 1  # XLA_FFI_Extension_Metadata
_F64 = 12  # XLA_FFI_DataType_F64 (xla::PrimitiveType F64)


class _Extension(ctypes.Structure):
    _fields_ = [("struct_size", ctypes.c_size_t), ("type", ctypes.c_int),
                ("next", ctypes.c_void_p)]


class _Version(ctypes.Structure):
    _fields_ = [("struct_size", ctypes.c_size_t), ("extension_start", ctypes.c_void_p),
                ("major", ctypes.c_int), ("minor", ctypes.c_int)]


class _Metadata(ctypes.Structure):
    _fields_ = [("struct_size", ctypes.c_size_t), ("api_version", _Version),
                ("traits", ctypes.c_uint32), ("state_type_id", ctypes.c_int64)]


class _MetadataExtension(ctypes.Structure):
    _fields_ = [("base", _Extension), ("metadata", ctypes.POINTER(_Metadata))]


class _Api(ctypes.Structure):
    _fields_ = [("struct_size", ctypes.c_size_t), ("extension_start", ctypes.c_void_p),
                ("api_version", _Version)]


class _Buffer(ctypes.Structure):
    _fields_ = [("struct_size", ctypes.c_size_t), ("extension_start", ctypes.c_void_p),
                ("dtype", ctypes.c_int), ("data", ctypes.c_void_p), ("rank", ctypes.c_int64),
                ("dims", ctypes.POINTER(ctypes.c_int64))]


class _Args(ctypes.Structure):
    _fields_ = [("struct_size", ctypes.c_size_t), ("extension_start", ctypes.c_void_p),
                ("size", ctypes.c_int64), ("types", ctypes.c_void_p),
                ("args", ctypes.POINTER(ctypes.c_void_p))]


class _CallFrame(ctypes.Structure):
    """The leading fields of XLA_FFI_CallFrame (xla/ffi/api/c_api.h)."""
    _fields_ = [("struct_size", ctypes.c_size_t),
                ("extension_start", ctypes.POINTER(_Extension)),
                ("api", ctypes.POINTER(_Api)), ("ctx", ctypes.c_void_p),
                ("stage", ctypes.c_int), ("args", _Args)]


_sink = None  # called with the reported time [s], or None
_lock = threading.Lock()
REPORTS = 1000
"""Reports per run at most (:class:`TimeReportingMeter`): one per 1/1000 of its time."""


def _handle(frame_pointer):
    """The FFI handler: answer XLA's metadata query, else pass the smallest reported
    time on to the sink. Returns NULL (success) always: a report must never fail a
    run."""
    try:
        frame = frame_pointer.contents
        if frame.extension_start and frame.extension_start.contents.type == _METADATA:
            metadata = ctypes.cast(frame.extension_start,
                                   ctypes.POINTER(_MetadataExtension)).contents.metadata.contents
            version = frame.api.contents.api_version
            metadata.api_version.major, metadata.api_version.minor = version.major, version.minor
            metadata.traits = 0
            return None
        sink = _sink
        if sink is None or frame.stage != _EXECUTE or frame.args.size < 1:
            return None
        buffer = ctypes.cast(frame.args.args[0], ctypes.POINTER(_Buffer)).contents
        if buffer.dtype != _F64:
            return None
        count = math.prod(buffer.dims[k] for k in range(buffer.rank))
        values = ctypes.cast(buffer.data, ctypes.POINTER(ctypes.c_double))
        sink(min(values[k] for k in range(count)))
    except Exception:  # noqa: BLE001 - never let a report break the run
        pass
    return None


_HANDLER = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.POINTER(_CallFrame))(_handle)
_registered = False


def register() -> None:
    """Register the FFI target for the CPU (once per process)."""
    global _registered
    if _registered:
        return
    capsule = ctypes.pythonapi.PyCapsule_New
    capsule.restype = ctypes.py_object
    capsule.argtypes = (ctypes.c_void_p, ctypes.c_char_p, ctypes.c_void_p)
    pointer = ctypes.cast(_HANDLER, ctypes.c_void_p).value
    jax.ffi.register_ffi_target(TARGET, capsule(pointer, None, None), platform="cpu")
    _registered = True


def report_time(t) -> None:
    """Report the simulated time ``t`` [s] (traced, float64) to the host; nothing on a
    backend other than the CPU. Not differentiated (its input is cut from the
    gradient); batched, it reports the smallest time of the batch."""
    if jax.default_backend() != "cpu":
        return
    register()
    call = jax.ffi.ffi_call(TARGET, (), has_side_effect=True, vmap_method="broadcast_all")
    call(jax.lax.stop_gradient(jnp.asarray(t, dtype=jnp.float64)))


class TimeReportingMeter(diffrax.AbstractProgressMeter):
    """A diffrax progress meter that reports the time of a solve from 0 to ``t1`` [s]
    (:func:`report_time`) after each step that enters a new 1/:data:`REPORTS` of the
    run; its state is the last such fraction reported (int32, -1 before the first).

    Not every step: a report enters Python through ``ctypes`` (about 30 us, 4 % of a
    table-mode IMEX step of the trailer), and a bar gains nothing from more than a few
    hundred positions."""

    t1: jax.Array

    def init(self):
        return jnp.asarray(-1, jnp.int32)

    def step(self, state, progress):
        reached = jnp.floor(jax.lax.stop_gradient(progress) * REPORTS).astype(jnp.int32)
        jax.lax.cond(reached > state, lambda: report_time(progress * self.t1), lambda: None)
        return jnp.maximum(state, reached)

    def close(self, state):
        pass


@contextlib.contextmanager
def listening(sink, interval: float = 0.1):
    """Within the block, pass reported times to ``sink(t)``, at most once per
    ``interval`` [s] of wall time (the times of accepted steps only ever grow)."""
    global _sink
    last = [-math.inf]  # wall time [s] of the last call of sink

    def throttled(t):
        now = time.monotonic()
        if now - last[0] >= interval:
            last[0] = now
            sink(t)

    with _lock:
        previous, _sink = _sink, throttled
    try:
        yield
    finally:
        with _lock:
            _sink = previous
