"""ctypes binding of the real tdvass shared library, for the robustness suite.

Only the standard library is used. The library is the one shipped in the
built FMU (``binaries/linux64/tdvass.so`` of ``target/fmu/tdvass.fmu``):

- ``$TDVASS_SO``: a shared library to load instead;
- ``$TDVASS_FMU``: the FMU to take it from;
- otherwise ``<target>/fmu/tdvass.fmu``, where ``<target>`` is
  ``$CARGO_TARGET_DIR`` or ``<repo>/target``.

The corner's FMU (``tdvass-corner.fmu`` next to it) carries the same
library: an ``Instance(lib, fmu=corner_fmu_file())`` is a corner, its GUID
and value references read from the corner's description; likewise the
chassis's (``tdvass-chassis.fmu``, ``chassis_fmu_file()``).

Every function takes raw ctypes arguments, so that the tests can pass NULL
pointers, wrong lengths and out-of-range values. The logger is a
``CFUNCTYPE`` with the fixed part of ``fmi2CallbackLogger``'s signature: the
FMU passes a pre-formatted message with every ``%`` doubled and never any
variadic argument, which makes this safe on x86-64 and aarch64.
"""

from __future__ import annotations

import ctypes
import os
import re
import tempfile
import zipfile
import zlib
from ctypes import (
    CFUNCTYPE,
    POINTER,
    Structure,
    byref,
    c_char,
    c_char_p,
    c_double,
    c_int,
    c_size_t,
    c_uint,
    c_void_p,
)
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]

OK, WARNING, DISCARD, ERROR, FATAL, PENDING = range(6)
STATUS_NAMES = ["fmi2OK", "fmi2Warning", "fmi2Discard", "fmi2Error", "fmi2Fatal", "fmi2Pending"]
MODEL_EXCHANGE, CO_SIMULATION = 0, 1
# Model Exchange: continuous states (in this order) and event indicators.
# (crates/tdvass/src/exchange/mod.rs, state_names).
STATE_NAMES = ["x_s", "v_s", "x_h", "v_h", "x_t", "v_t", *[f"wk_filter_{k}" for k in range(1, 9)],
               "integral_body_acceleration_squared", "integral_suspension_deflection_squared",
               "integral_tire_deflection_squared", "integral_weighted_acceleration_squared",
               "integral_weighted_acceleration_fourth", "contact_loss_time"]
NX, NZ = 20, 1
DO_STEP_STATUS, PENDING_STATUS, LAST_SUCCESSFUL_TIME, TERMINATED = range(4)

fmi2Component = c_void_p
fmi2FMUstate = c_void_p
fmi2ValueReference = c_uint
fmi2Real = c_double
fmi2Integer = c_int
fmi2Boolean = c_int
fmi2Status = c_int
fmi2String = c_char_p

LOGGER = CFUNCTYPE(None, c_void_p, c_char_p, c_int, c_char_p, c_char_p)
ALLOCATE = CFUNCTYPE(c_void_p, c_size_t, c_size_t)
FREE = CFUNCTYPE(None, c_void_p)
STEP_FINISHED = CFUNCTYPE(None, c_void_p, c_int)


class EventInfo(Structure):
    """``fmi2EventInfo``, filled with sentinels (-1, NaN) so that a test sees
    what the FMU wrote."""

    _fields_ = [
        ("newDiscreteStatesNeeded", fmi2Boolean),
        ("terminateSimulation", fmi2Boolean),
        ("nominalsOfContinuousStatesChanged", fmi2Boolean),
        ("valuesOfContinuousStatesChanged", fmi2Boolean),
        ("nextEventTimeDefined", fmi2Boolean),
        ("nextEventTime", fmi2Real),
    ]

    def __init__(self):
        super().__init__(-1, -1, -1, -1, -1, float("nan"))


class CallbackFunctions(Structure):
    _fields_ = [
        ("logger", LOGGER),
        ("allocateMemory", ALLOCATE),
        ("freeMemory", FREE),
        ("stepFinished", STEP_FINISHED),
        ("componentEnvironment", c_void_p),
    ]


def target_dir() -> Path:
    target = os.environ.get("CARGO_TARGET_DIR")
    path = Path(target) if target else REPO_ROOT / "target"
    return path if path.is_absolute() else REPO_ROOT / path


def fmu_file() -> Path:
    override = os.environ.get("TDVASS_FMU")
    return Path(override) if override else target_dir() / "fmu" / "tdvass.fmu"


def corner_fmu_file() -> Path:
    """The corner's FMU, next to the quarter car's."""
    return fmu_file().with_name("tdvass-corner.fmu")


def chassis_fmu_file() -> Path:
    """The chassis's FMU, next to the quarter car's."""
    return fmu_file().with_name("tdvass-chassis.fmu")


def model_description(fmu: Path | None = None) -> str:
    with zipfile.ZipFile(fmu or fmu_file()) as z:
        return z.read("modelDescription.xml").decode()


def library_path() -> Path:
    """The shared library to test (extracted from the FMU once per process)."""
    override = os.environ.get("TDVASS_SO")
    if override:
        return Path(override)
    fmu = fmu_file()
    if not fmu.is_file():
        raise FileNotFoundError(f"{fmu} not found; build it with `cargo run --release -p fmu-build`")
    out = Path(tempfile.mkdtemp(prefix="tdvass-robustness-")) / "tdvass.so"
    with zipfile.ZipFile(fmu) as z:
        out.write_bytes(z.read("binaries/linux64/tdvass.so"))
    return out


def variables(fmu: Path | None = None) -> dict[str, tuple[int, str, str, str]]:
    """name -> (value reference, type, causality, variability) from modelDescription.xml."""
    xml = model_description(fmu)
    found = {}
    pattern = re.compile(
        r'<ScalarVariable\s+name="([^"]+)"\s+valueReference="(\d+)"([^>]*)>\s*<(Real|Integer|Boolean|String)',
        re.S,
    )
    for name, vr, attributes, kind in pattern.findall(xml):
        causality = re.search(r'causality="(\w+)"', attributes)
        variability = re.search(r'variability="(\w+)"', attributes)
        found[name] = (
            int(vr),
            kind,
            causality.group(1) if causality else "local",
            variability.group(1) if variability else "continuous",
        )
    return found


def guid(fmu: Path | None = None) -> str:
    return re.search(r'guid="([^"]+)"', model_description(fmu)).group(1)


_SIGNATURES = {
    "fmi2GetTypesPlatform": (c_char_p, []),
    "fmi2GetVersion": (c_char_p, []),
    "fmi2SetDebugLogging": (fmi2Status, [fmi2Component, fmi2Boolean, c_size_t, c_void_p]),
    "fmi2Instantiate": (
        fmi2Component,
        [c_char_p, c_int, c_char_p, c_char_p, c_void_p, fmi2Boolean, fmi2Boolean],
    ),
    "fmi2FreeInstance": (None, [fmi2Component]),
    "fmi2SetupExperiment": (
        fmi2Status,
        [fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real],
    ),
    "fmi2EnterInitializationMode": (fmi2Status, [fmi2Component]),
    "fmi2ExitInitializationMode": (fmi2Status, [fmi2Component]),
    "fmi2Terminate": (fmi2Status, [fmi2Component]),
    "fmi2Reset": (fmi2Status, [fmi2Component]),
    "fmi2GetReal": (fmi2Status, [fmi2Component, c_void_p, c_size_t, c_void_p]),
    "fmi2GetInteger": (fmi2Status, [fmi2Component, c_void_p, c_size_t, c_void_p]),
    "fmi2GetBoolean": (fmi2Status, [fmi2Component, c_void_p, c_size_t, c_void_p]),
    "fmi2GetString": (fmi2Status, [fmi2Component, c_void_p, c_size_t, c_void_p]),
    "fmi2SetReal": (fmi2Status, [fmi2Component, c_void_p, c_size_t, c_void_p]),
    "fmi2SetInteger": (fmi2Status, [fmi2Component, c_void_p, c_size_t, c_void_p]),
    "fmi2SetBoolean": (fmi2Status, [fmi2Component, c_void_p, c_size_t, c_void_p]),
    "fmi2SetString": (fmi2Status, [fmi2Component, c_void_p, c_size_t, c_void_p]),
    "fmi2GetFMUstate": (fmi2Status, [fmi2Component, c_void_p]),
    "fmi2SetFMUstate": (fmi2Status, [fmi2Component, fmi2FMUstate]),
    "fmi2FreeFMUstate": (fmi2Status, [fmi2Component, c_void_p]),
    "fmi2SerializedFMUstateSize": (fmi2Status, [fmi2Component, fmi2FMUstate, c_void_p]),
    "fmi2SerializeFMUstate": (fmi2Status, [fmi2Component, fmi2FMUstate, c_void_p, c_size_t]),
    "fmi2DeSerializeFMUstate": (fmi2Status, [fmi2Component, c_void_p, c_size_t, c_void_p]),
    "fmi2GetDirectionalDerivative": (
        fmi2Status,
        [fmi2Component, c_void_p, c_size_t, c_void_p, c_size_t, c_void_p, c_void_p],
    ),
    "fmi2SetRealInputDerivatives": (
        fmi2Status,
        [fmi2Component, c_void_p, c_size_t, c_void_p, c_void_p],
    ),
    "fmi2GetRealOutputDerivatives": (
        fmi2Status,
        [fmi2Component, c_void_p, c_size_t, c_void_p, c_void_p],
    ),
    "fmi2DoStep": (fmi2Status, [fmi2Component, fmi2Real, fmi2Real, fmi2Boolean]),
    "fmi2CancelStep": (fmi2Status, [fmi2Component]),
    "fmi2GetStatus": (fmi2Status, [fmi2Component, c_int, c_void_p]),
    "fmi2GetRealStatus": (fmi2Status, [fmi2Component, c_int, c_void_p]),
    "fmi2GetIntegerStatus": (fmi2Status, [fmi2Component, c_int, c_void_p]),
    "fmi2GetBooleanStatus": (fmi2Status, [fmi2Component, c_int, c_void_p]),
    "fmi2GetStringStatus": (fmi2Status, [fmi2Component, c_int, c_void_p]),
    # Model Exchange (the pointers stay c_void_p, so that the tests can pass
    # NULL, arrays of any length and `byref` of an EventInfo or c_int).
    "fmi2EnterEventMode": (fmi2Status, [fmi2Component]),
    "fmi2NewDiscreteStates": (fmi2Status, [fmi2Component, c_void_p]),
    "fmi2EnterContinuousTimeMode": (fmi2Status, [fmi2Component]),
    "fmi2CompletedIntegratorStep": (fmi2Status, [fmi2Component, fmi2Boolean, c_void_p, c_void_p]),
    "fmi2SetTime": (fmi2Status, [fmi2Component, fmi2Real]),
    "fmi2SetContinuousStates": (fmi2Status, [fmi2Component, c_void_p, c_size_t]),
    "fmi2GetDerivatives": (fmi2Status, [fmi2Component, c_void_p, c_size_t]),
    "fmi2GetEventIndicators": (fmi2Status, [fmi2Component, c_void_p, c_size_t]),
    "fmi2GetContinuousStates": (fmi2Status, [fmi2Component, c_void_p, c_size_t]),
    "fmi2GetNominalsOfContinuousStates": (fmi2Status, [fmi2Component, c_void_p, c_size_t]),
}


def load(path: Path | None = None) -> ctypes.CDLL:
    lib = ctypes.CDLL(str(path or library_path()))
    for name, (restype, argtypes) in _SIGNATURES.items():
        f = getattr(lib, name)
        f.restype = restype
        f.argtypes = argtypes
    return lib


class Log:
    """Messages logged through one set of callbacks: (status, category, message)."""

    _all: dict[int, Log] = {}

    def __init__(self):
        self.messages: list[tuple[int, str, str]] = []
        self.key = len(Log._all) + 1
        Log._all[self.key] = self  # kept: an instance may log until it is freed
        self.callbacks = CallbackFunctions(
            LOGGER(Log._dispatch), ALLOCATE(0), FREE(0), STEP_FINISHED(0), self.key
        )

    @staticmethod
    def _dispatch(environment, _name, status, category, message):
        log = Log._all.get(environment or 0)
        if log is not None:
            text = (message or b"").decode(errors="replace").replace("%%", "%")
            log.messages.append((status, (category or b"").decode(), text))

    def last(self) -> tuple[int, str, str]:
        return self.messages[-1] if self.messages else (-1, "", "")

    def since(self, count: int) -> list[tuple[int, str, str]]:
        return self.messages[count:]


def array(ctype, values):
    values = list(values)
    return (ctype * max(len(values), 1))(*values)


def serialized_fields(data: bytes) -> tuple[int, int]:
    """(offset of the payload, its length) of a serialized FMU state."""
    guid_len = int.from_bytes(data[12:16], "little")
    payload_at = 16 + guid_len + 12
    return payload_at, len(data) - payload_at


def reseal(data: bytes | bytearray) -> bytes:
    """The bytes with the header's CRC-32 recomputed over the payload (to
    reach the checks behind the checksum)."""
    data = bytearray(data)
    guid_len = int.from_bytes(data[12:16], "little")
    payload_at = 16 + guid_len + 12
    crc = zlib.crc32(bytes(data[payload_at:])) & 0xFFFFFFFF
    data[payload_at - 4 : payload_at] = crc.to_bytes(4, "little")
    return bytes(data)


DEFAULT = object()


class Instance:
    """One instance: thin methods that return the raw fmi2Status. ``fmu``:
    the FMU whose description gives the GUID and the value references (the
    quarter car's by default)."""

    def __init__(self, lib, name: bytes | None = b"robust", fmu_type=CO_SIMULATION, guid_=DEFAULT,
                 resources: bytes | None = b"file:///tmp/resources", logging_on=0, log: Log | None = None,
                 fmu: Path | None = None):
        self.lib = lib
        self.log = log or Log()
        self.vr = {k: v[0] for k, v in variables(fmu).items()}
        g = guid(fmu).encode() if guid_ is DEFAULT else guid_
        self.c = lib.fmi2Instantiate(name, fmu_type, g, resources, byref(self.log.callbacks), 0, logging_on)
        self.time = 0.0

    @property
    def ok(self) -> bool:
        return bool(self.c)

    def free(self):
        if self.c:
            self.lib.fmi2FreeInstance(self.c)
            self.c = None

    # --------------------------------------------------------------- life cycle

    def setup(self, start=0.0, stop=None):
        return self.lib.fmi2SetupExperiment(self.c, 0, 0.0, start, stop is not None, stop or 0.0)

    def enter(self):
        return self.lib.fmi2EnterInitializationMode(self.c)

    def exit(self):
        return self.lib.fmi2ExitInitializationMode(self.c)

    def initialize(self, start=0.0, stop=None, **values):
        assert self.setup(start, stop) == OK, self.log.last()
        status = self.set(**values)
        assert status == OK, self.log.last()
        assert self.enter() == OK
        status = self.exit()
        assert status in (OK, WARNING), self.log.last()
        self.time = start
        return status

    def step(self, h, t=None):
        t = self.time if t is None else t
        status = self.lib.fmi2DoStep(self.c, t, h, 1)
        if status == OK:
            self.time = t + h
        return status

    # ------------------------------------------------------------------ values

    def set(self, **values):
        status = OK
        for name, value in values.items():
            if isinstance(value, bool):
                s = self.set_boolean([self.vr[name]], [value])
            elif isinstance(value, int):
                s = self.set_integer([self.vr[name]], [value])
            else:
                s = self.set_real([self.vr[name]], [value])
            status = max(status, s)
        return status

    def set_real(self, vrs, values):
        return self.lib.fmi2SetReal(self.c, array(c_uint, vrs), len(vrs), array(c_double, values))

    def set_integer(self, vrs, values):
        return self.lib.fmi2SetInteger(self.c, array(c_uint, vrs), len(vrs), array(c_int, values))

    def set_boolean(self, vrs, values):
        return self.lib.fmi2SetBoolean(self.c, array(c_uint, vrs), len(vrs), array(c_int, values))

    def get_real(self, vrs):
        out = (c_double * max(len(vrs), 1))()
        status = self.lib.fmi2GetReal(self.c, array(c_uint, vrs), len(vrs), out)
        return status, list(out[: len(vrs)])

    def get(self, *names):
        status, values = self.get_real([self.vr[n] for n in names])
        assert status == OK, self.log.last()
        return values

    def real_status(self, kind=LAST_SUCCESSFUL_TIME):
        out = c_double(float("nan"))
        status = self.lib.fmi2GetRealStatus(self.c, kind, byref(out))
        return status, out.value

    def boolean_status(self, kind=TERMINATED):
        out = c_int(-1)
        status = self.lib.fmi2GetBooleanStatus(self.c, kind, byref(out))
        return status, out.value

    # ---------------------------------------------------------- Model Exchange

    def initialize_model_exchange(self, start=0.0, stop=None, **values):
        """An instance made with fmu_type=MODEL_EXCHANGE, initialized: in
        eventMode at `start`."""
        status = self.initialize(start, stop, **values)
        assert self.machine_state() == "eventMode"
        return status

    def enter_event_mode(self):
        return self.lib.fmi2EnterEventMode(self.c)

    def enter_continuous_time_mode(self):
        return self.lib.fmi2EnterContinuousTimeMode(self.c)

    def new_discrete_states(self):
        """fmi2NewDiscreteStates: (status, EventInfo)."""
        info = EventInfo()
        status = self.lib.fmi2NewDiscreteStates(self.c, byref(info))
        return status, info

    def completed_integrator_step(self, no_set_prior=1):
        """fmi2CompletedIntegratorStep: (status, enterEventMode, terminateSimulation)."""
        enter, terminate = c_int(-1), c_int(-1)
        status = self.lib.fmi2CompletedIntegratorStep(self.c, no_set_prior, byref(enter), byref(terminate))
        return status, enter.value, terminate.value

    def set_time(self, t):
        return self.lib.fmi2SetTime(self.c, t)

    def set_continuous_states(self, values):
        values = list(values)
        return self.lib.fmi2SetContinuousStates(self.c, array(c_double, values), len(values))

    def _vector(self, function, n):
        out = (c_double * max(n, 1))(*([float("nan")] * max(n, 1)))
        status = getattr(self.lib, function)(self.c, out, n)
        return status, list(out[:n])

    def continuous_states(self, n=NX):
        return self._vector("fmi2GetContinuousStates", n)

    def derivatives(self, n=NX):
        return self._vector("fmi2GetDerivatives", n)

    def event_indicators(self, n=NZ):
        return self._vector("fmi2GetEventIndicators", n)

    def nominals(self, n=NX):
        return self._vector("fmi2GetNominalsOfContinuousStates", n)

    def euler_step(self, h):
        """One explicit Euler step of size h in continuousTimeMode, completed:
        the status of fmi2CompletedIntegratorStep's call, its two flags."""
        status, x = self.continuous_states()
        assert status == OK, self.log.last()
        status, dx = self.derivatives()
        assert status == OK, self.log.last()
        assert self.set_time(self.time + h) == OK, self.log.last()
        self.time += h
        assert self.set_continuous_states([a + h * b for a, b in zip(x, dx)]) == OK, self.log.last()
        return self.completed_integrator_step()

    # -------------------------------------------------------------- FMU states

    def get_state(self):
        s = fmi2FMUstate()
        status = self.lib.fmi2GetFMUstate(self.c, byref(s))
        return status, s

    def serialize(self, state) -> bytes:
        size = c_size_t()
        assert self.lib.fmi2SerializedFMUstateSize(self.c, state, byref(size)) == OK
        buf = (c_char * size.value)()
        assert self.lib.fmi2SerializeFMUstate(self.c, state, buf, size.value) == OK
        return bytes(buf)

    def deserialize(self, data: bytes):
        s = fmi2FMUstate()
        buf = (c_char * max(len(data), 1)).from_buffer_copy(data or b"\0")
        status = self.lib.fmi2DeSerializeFMUstate(self.c, buf, len(data), byref(s))
        return status, s

    def snapshot(self) -> bytes:
        """The serialized bytes of the current state (everything an FMU state
        holds), without leaving an FMU state behind."""
        status, state = self.get_state()
        assert status == OK, self.log.last()
        data = self.serialize(state)
        assert self.lib.fmi2FreeFMUstate(self.c, byref(state)) == OK
        return data

    def machine_state(self) -> str:
        """The machine state, read without changing anything: fmi2CancelStep
        is allowed in no state, so its refusal names the current one."""
        before = len(self.log.messages)
        assert self.lib.fmi2CancelStep(self.c) == ERROR
        message = self.log.since(before)[-1][2]
        m = re.fullmatch(r"fmi2CancelStep: not allowed in state (\w+)", message)
        assert m, message
        return m.group(1)
