"""ctypes binding of the real tdvass FMI 3.0 shared library, for the
robustness suite.

Only the standard library is used. The library is the one shipped in the
built FMU (``binaries/x86_64-linux/tdvass.so`` of
``target/fmu/tdvass-fmi3.fmu``):

- ``$TDVASS_FMI3_SO``: a shared library to load instead;
- ``$TDVASS_FMI3_FMU``: the FMU to take it from;
- otherwise ``<target>/fmu/tdvass-fmi3.fmu``, where ``<target>`` is
  ``$CARGO_TARGET_DIR`` or ``<repo>/target``.

The instantiation token and the value references are read from the FMU's
modelDescription.xml. The corner's FMU (``tdvass-corner-fmi3.fmu`` next to
it) carries the same library: an ``Instance(lib, fmu=corner_fmu_file())`` is
a corner; likewise the chassis's (``tdvass-chassis-fmi3.fmu``,
``chassis_fmu_file()``). Every function takes raw ctypes arguments, so that
the tests can pass NULL pointers, wrong lengths and out-of-range values.
``fmi3Boolean`` is a C ``bool`` (one byte): ``c_bool``.
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
    byref,
    c_bool,
    c_char_p,
    c_double,
    c_int,
    c_int32,
    c_int64,
    c_size_t,
    c_uint8,
    c_uint32,
    c_uint64,
    c_void_p,
)
from pathlib import Path

from fmi2 import NX, NZ, REPO_ROOT, STATE_NAMES, array, target_dir  # noqa: F401 (re-exported)

OK, WARNING, DISCARD, ERROR, FATAL = range(5)
STATUS_NAMES = ["fmi3OK", "fmi3Warning", "fmi3Discard", "fmi3Error", "fmi3Fatal"]

fmi3Instance = c_void_p
fmi3FMUState = c_void_p
fmi3ValueReference = c_uint32
fmi3Float64 = c_double
fmi3Boolean = c_bool
fmi3Status = c_int

LOG_MESSAGE = CFUNCTYPE(None, c_void_p, c_int, c_char_p, c_char_p)
INTERMEDIATE_UPDATE = CFUNCTYPE(
    None, c_void_p, c_double, c_bool, c_bool, c_bool, c_bool, POINTER(c_bool), POINTER(c_double)
)

FFI_RS = REPO_ROOT / "crates" / "tdvass-fmi3" / "src" / "ffi.rs"
STATES_RS = REPO_ROOT / "crates" / "tdvass-fmi3" / "src" / "states.rs"


def fmu_file() -> Path:
    override = os.environ.get("TDVASS_FMI3_FMU")
    return Path(override) if override else target_dir() / "fmu" / "tdvass-fmi3.fmu"


def corner_fmu_file() -> Path:
    """The corner's FMU, next to the quarter car's."""
    return fmu_file().with_name("tdvass-corner-fmi3.fmu")


def chassis_fmu_file() -> Path:
    """The chassis's FMU, next to the quarter car's."""
    return fmu_file().with_name("tdvass-chassis-fmi3.fmu")


def model_description(fmu: Path | None = None) -> str:
    with zipfile.ZipFile(fmu or fmu_file()) as z:
        return z.read("modelDescription.xml").decode()


def library_path() -> Path:
    """The shared library to test (extracted from the FMU once per process)."""
    override = os.environ.get("TDVASS_FMI3_SO")
    if override:
        return Path(override)
    fmu = fmu_file()
    if not fmu.is_file():
        raise FileNotFoundError(f"{fmu} not found; build it with `cargo run --release -p fmu-build`")
    out = Path(tempfile.mkdtemp(prefix="tdvass-robustness-fmi3-")) / "tdvass.so"
    with zipfile.ZipFile(fmu) as z:
        out.write_bytes(z.read("binaries/x86_64-linux/tdvass.so"))
    return out


def variables(fmu: Path | None = None) -> dict[str, tuple[int, str, str, str]]:
    """name -> (value reference, type, causality, variability) from modelDescription.xml."""
    xml = model_description(fmu)
    variables_xml = xml[xml.index("<ModelVariables>") :]
    found = {}
    for kind, attributes in re.findall(r"<(Float64|Int32|Int64|UInt64|Boolean|Enumeration)\s([^>]*)>",
                                       variables_xml):
        name = re.search(r'\bname="([^"]+)"', attributes).group(1)
        vr = int(re.search(r'\bvalueReference="(\d+)"', attributes).group(1))
        causality = re.search(r'\bcausality="(\w+)"', attributes)
        variability = re.search(r'\bvariability="(\w+)"', attributes)
        found[name] = (
            vr,
            kind,
            causality.group(1) if causality else "local",
            variability.group(1) if variability else "continuous",
        )
    return found


def instantiation_token(fmu: Path | None = None) -> str:
    return re.search(r'instantiationToken="([^"]+)"', model_description(fmu)).group(1)


def exported_functions() -> list[str]:
    """Every fmi3 function ffi.rs exports (plain functions and the macros
    that generate the getters and setters and the refused functions)."""
    source = FFI_RS.read_text()
    names = re.findall(r'pub (?:unsafe )?extern "C" fn (fmi3\w+)', source)
    for getter, setter in re.findall(r"(?:unused_type|accessors)!\(\s*(fmi3\w+),\s*(fmi3\w+)", source):
        names += [getter, setter]
    names += re.findall(r"^refused!\((fmi3\w+)", source, re.M)
    return sorted(names)


P = c_void_p
_VALUE_FUNCTIONS = {
    "fmi3GetFloat32": ctypes.c_float, "fmi3GetFloat64": c_double, "fmi3GetInt8": ctypes.c_int8,
    "fmi3GetUInt8": c_uint8, "fmi3GetInt16": ctypes.c_int16, "fmi3GetUInt16": ctypes.c_uint16,
    "fmi3GetInt32": c_int32, "fmi3GetUInt32": c_uint32, "fmi3GetInt64": c_int64, "fmi3GetUInt64": c_uint64,
    "fmi3GetBoolean": c_bool, "fmi3GetString": c_char_p,
}
# The C type of each getter's (and setter's) values.
VALUE_TYPES = {**_VALUE_FUNCTIONS, **{k.replace("Get", "Set"): v for k, v in _VALUE_FUNCTIONS.items()}}

_SIGNATURES = {
    "fmi3GetVersion": (c_char_p, []),
    "fmi3SetDebugLogging": (fmi3Status, [P, c_bool, c_size_t, P]),
    "fmi3InstantiateModelExchange": (P, [c_char_p, c_char_p, c_char_p, c_bool, c_bool, P, P]),
    "fmi3InstantiateCoSimulation": (
        P,
        [c_char_p, c_char_p, c_char_p, c_bool, c_bool, c_bool, c_bool, P, c_size_t, P, P, P],
    ),
    "fmi3InstantiateScheduledExecution": (
        P,
        [c_char_p, c_char_p, c_char_p, c_bool, c_bool, P, P, P, P, P],
    ),
    "fmi3FreeInstance": (None, [P]),
    "fmi3EnterInitializationMode": (fmi3Status, [P, c_bool, c_double, c_double, c_bool, c_double]),
    "fmi3ExitInitializationMode": (fmi3Status, [P]),
    "fmi3EnterEventMode": (fmi3Status, [P]),
    "fmi3Terminate": (fmi3Status, [P]),
    "fmi3Reset": (fmi3Status, [P]),
    **{name: (fmi3Status, [P, P, c_size_t, P, c_size_t]) for name in VALUE_TYPES},
    "fmi3GetBinary": (fmi3Status, [P, P, c_size_t, P, P, c_size_t]),
    "fmi3SetBinary": (fmi3Status, [P, P, c_size_t, P, P, c_size_t]),
    "fmi3GetClock": (fmi3Status, [P, P, c_size_t, P]),
    "fmi3SetClock": (fmi3Status, [P, P, c_size_t, P]),
    "fmi3GetNumberOfVariableDependencies": (fmi3Status, [P, c_uint32, P]),
    "fmi3GetVariableDependencies": (fmi3Status, [P, c_uint32, P, P, P, P, c_size_t]),
    "fmi3GetFMUState": (fmi3Status, [P, P]),
    "fmi3SetFMUState": (fmi3Status, [P, fmi3FMUState]),
    "fmi3FreeFMUState": (fmi3Status, [P, P]),
    "fmi3SerializedFMUStateSize": (fmi3Status, [P, fmi3FMUState, P]),
    "fmi3SerializeFMUState": (fmi3Status, [P, fmi3FMUState, P, c_size_t]),
    "fmi3DeserializeFMUState": (fmi3Status, [P, P, c_size_t, P]),
    "fmi3GetDirectionalDerivative": (fmi3Status, [P, P, c_size_t, P, c_size_t, P, c_size_t, P, c_size_t]),
    "fmi3GetAdjointDerivative": (fmi3Status, [P, P, c_size_t, P, c_size_t, P, c_size_t, P, c_size_t]),
    "fmi3EnterConfigurationMode": (fmi3Status, [P]),
    "fmi3ExitConfigurationMode": (fmi3Status, [P]),
    "fmi3GetIntervalDecimal": (fmi3Status, [P, P, c_size_t, P, P]),
    "fmi3GetIntervalFraction": (fmi3Status, [P, P, c_size_t, P, P, P]),
    "fmi3GetShiftDecimal": (fmi3Status, [P, P, c_size_t, P]),
    "fmi3GetShiftFraction": (fmi3Status, [P, P, c_size_t, P, P]),
    "fmi3SetIntervalDecimal": (fmi3Status, [P, P, c_size_t, P]),
    "fmi3SetIntervalFraction": (fmi3Status, [P, P, c_size_t, P, P]),
    "fmi3SetShiftDecimal": (fmi3Status, [P, P, c_size_t, P]),
    "fmi3SetShiftFraction": (fmi3Status, [P, P, c_size_t, P, P]),
    "fmi3EvaluateDiscreteStates": (fmi3Status, [P]),
    "fmi3UpdateDiscreteStates": (fmi3Status, [P, P, P, P, P, P, P]),
    "fmi3EnterContinuousTimeMode": (fmi3Status, [P]),
    "fmi3CompletedIntegratorStep": (fmi3Status, [P, c_bool, P, P]),
    "fmi3SetTime": (fmi3Status, [P, c_double]),
    "fmi3SetContinuousStates": (fmi3Status, [P, P, c_size_t]),
    "fmi3GetContinuousStateDerivatives": (fmi3Status, [P, P, c_size_t]),
    "fmi3GetEventIndicators": (fmi3Status, [P, P, c_size_t]),
    "fmi3GetContinuousStates": (fmi3Status, [P, P, c_size_t]),
    "fmi3GetNominalsOfContinuousStates": (fmi3Status, [P, P, c_size_t]),
    "fmi3GetNumberOfEventIndicators": (fmi3Status, [P, P]),
    "fmi3GetNumberOfContinuousStates": (fmi3Status, [P, P]),
    "fmi3GetOutputDerivatives": (fmi3Status, [P, P, c_size_t, P, P, c_size_t]),
    "fmi3DoStep": (fmi3Status, [P, c_double, c_double, c_bool, P, P, P, P]),
    "fmi3EnterStepMode": (fmi3Status, [P]),
    "fmi3ActivateModelPartition": (fmi3Status, [P, c_uint32, c_double]),
}


def load(path: Path | None = None) -> ctypes.CDLL:
    lib = ctypes.CDLL(str(path or library_path()))
    for name, (restype, argtypes) in _SIGNATURES.items():
        f = getattr(lib, name)
        f.restype = restype
        f.argtypes = argtypes
    return lib


class Log:
    """Messages logged through one environment: (status, category, message)."""

    _all: dict[int, Log] = {}

    def __init__(self):
        self.messages: list[tuple[int, str, str]] = []
        self.key = len(Log._all) + 1
        Log._all[self.key] = self  # kept: an instance may log until it is freed

    @staticmethod
    def _dispatch(environment, status, category, message):
        log = Log._all.get(environment or 0)
        if log is not None:
            text = (message or b"").decode(errors="replace")
            log.messages.append((status, (category or b"").decode(), text))

    def last(self) -> tuple[int, str, str]:
        return self.messages[-1] if self.messages else (-1, "", "")

    def since(self, count: int) -> list[tuple[int, str, str]]:
        return self.messages[count:]


LOGGER = LOG_MESSAGE(Log._dispatch)


def serialized_fields(data: bytes) -> tuple[int, int]:
    """(offset of the payload, its length) of a serialized FMU state (the
    format the FMI 2.0 FMU writes, under the instantiation token)."""
    token_len = int.from_bytes(data[12:16], "little")
    payload_at = 16 + token_len + 12
    return payload_at, len(data) - payload_at


def reseal(data: bytes | bytearray) -> bytes:
    """The bytes with the header's CRC-32 recomputed over the payload."""
    data = bytearray(data)
    payload_at, _ = serialized_fields(bytes(data))
    crc = zlib.crc32(bytes(data[payload_at:])) & 0xFFFFFFFF
    data[payload_at - 4 : payload_at] = crc.to_bytes(4, "little")
    return bytes(data)


DEFAULT = object()


class Instance:
    """One Co-Simulation instance (``model_exchange=True``: a Model Exchange
    instance, made by fmi3InstantiateModelExchange), with thin methods that
    return the raw fmi3Status.

    ``intermediate``: a Python function ``f(inst, time, can_return_early)``
    called from the FMU's intermediateUpdate callback; it returns whether to
    ask for an early return. Exceptions raised inside it are kept in
    ``callback_errors`` (ctypes would only print them).

    ``fmu``: the FMU whose description gives the instantiation token and the
    value references (the quarter car's by default).
    """

    _all: dict[int, Instance] = {}

    def __init__(self, lib, name: bytes | None = b"robust", token=DEFAULT, resources: bytes | None = None,
                 logging_on=False, early_return=False, intermediate=None, required=(), event_mode=False,
                 log: Log | None = None, model_exchange=False, fmu: Path | None = None):
        self.lib = lib
        self.log = log or Log()
        self.vars = variables(fmu)
        self.vr = {k: v[0] for k, v in self.vars.items()}
        self.intermediate = intermediate
        self.callback_errors: list[BaseException] = []
        self.updates: list[float] = []
        Instance._all[self.log.key] = self
        t = instantiation_token(fmu).encode() if token is DEFAULT else token
        self._callback = INTERMEDIATE_UPDATE(Instance._intermediate) if intermediate else None
        required = list(required)
        self.model_exchange = model_exchange
        if model_exchange:
            self.c = lib.fmi3InstantiateModelExchange(name, t, resources, False, logging_on, self.log.key, LOGGER)
        else:
            self.c = lib.fmi3InstantiateCoSimulation(
                name, t, resources, False, logging_on, event_mode, early_return,
                array(c_uint32, required) if required else None, len(required),
                self.log.key, LOGGER, self._callback,
            )
        self.time = 0.0

    @staticmethod
    def _intermediate(environment, time, _clock_active, _set_requested, _get_allowed, can_return_early,
                      early_return_requested, early_return_time):
        inst = Instance._all.get(environment or 0)
        if inst is None or inst.intermediate is None:
            return
        inst.updates.append(time)
        try:
            if inst.intermediate(inst, time, can_return_early):
                early_return_requested[0] = True
                early_return_time[0] = time
        except BaseException as e:  # noqa: BLE001 (reported after the step)
            inst.callback_errors.append(e)

    @property
    def ok(self) -> bool:
        return bool(self.c)

    def free(self):
        if self.c:
            self.lib.fmi3FreeInstance(self.c)
            self.c = None

    # --------------------------------------------------------------- life cycle

    def enter(self, start=0.0, stop=None):
        return self.lib.fmi3EnterInitializationMode(self.c, False, 0.0, start, stop is not None, stop or 0.0)

    def exit(self):
        return self.lib.fmi3ExitInitializationMode(self.c)

    def initialize(self, start=0.0, stop=None, **values):
        status = self.set(**values)
        assert status == OK, self.log.last()
        assert self.enter(start, stop) == OK, self.log.last()
        status = self.exit()
        assert status in (OK, WARNING), self.log.last()
        self.time = start
        return status

    def do_step(self, t, h, event=DEFAULT, terminate=DEFAULT, early=DEFAULT, last=DEFAULT):
        """fmi3DoStep with the four out-values: (status, eventHandlingNeeded,
        terminateSimulation, earlyReturn, lastSuccessfulTime). Pass None for
        an out-pointer to pass NULL."""
        outs = [c_bool(True), c_bool(True), c_bool(True), c_double(float("nan"))]
        pointers = [None if given is None else byref(out) for given, out in zip((event, terminate, early, last), outs)]
        status = self.lib.fmi3DoStep(self.c, t, h, False, *pointers)
        for e in self.callback_errors:
            raise e
        return (status, *(o.value for o in outs))

    def step(self, h, t=None):
        t = self.time if t is None else t
        status, _, _, early, last = self.do_step(t, h)
        if status == OK:
            self.time = last if early else t + h
        return status

    # ------------------------------------------------------------------ values

    def set(self, **values):
        status = OK
        for name, value in values.items():
            kind = self.vars[name][1]
            vr = [self.vr[name]]
            if kind == "Boolean":
                s = self.set_values("fmi3SetBoolean", vr, [value])
            elif kind == "Int32":
                s = self.set_values("fmi3SetInt32", vr, [value])
            elif kind == "Enumeration":
                s = self.set_values("fmi3SetInt64", vr, [value])
            elif kind == "UInt64":
                s = self.set_values("fmi3SetUInt64", vr, [value])
            else:
                s = self.set_values("fmi3SetFloat64", vr, [value])
            status = max(status, s)
        return status

    def set_values(self, function, vrs, values):
        ctype = VALUE_TYPES[function]
        return getattr(self.lib, function)(self.c, array(c_uint32, vrs), len(vrs), array(ctype, values), len(values))

    def get_values(self, function, vrs, n=None):
        n = len(vrs) if n is None else n
        out = (VALUE_TYPES[function] * max(n, 1))()
        status = getattr(self.lib, function)(self.c, array(c_uint32, vrs), len(vrs), out, n)
        return status, list(out[:n])

    def get_float64(self, vrs, n=None):
        return self.get_values("fmi3GetFloat64", vrs, n)

    def get(self, *names):
        status, values = self.get_float64([self.vr[n] for n in names])
        assert status == OK, self.log.last()
        return values

    # ---------------------------------------------------------- Model Exchange

    def initialize_model_exchange(self, start=0.0, stop=None, **values):
        """A Model Exchange instance, initialized: in Event Mode at `start`."""
        status = self.initialize(start, stop, **values)
        assert self.machine_state() == "Event Mode"
        return status

    def enter_event_mode(self):
        return self.lib.fmi3EnterEventMode(self.c)

    def enter_continuous_time_mode(self):
        return self.lib.fmi3EnterContinuousTimeMode(self.c)

    def update_discrete_states(self):
        """fmi3UpdateDiscreteStates: (status, discreteStatesNeedUpdate,
        terminateSimulation, nominalsOfContinuousStatesChanged,
        valuesOfContinuousStatesChanged, nextEventTimeDefined, nextEventTime);
        the flags read as bytes (the FMU must write 0 or 1)."""
        flags = [c_uint8(0xAA) for _ in range(5)]
        next_time = c_double(float("nan"))
        status = self.lib.fmi3UpdateDiscreteStates(self.c, *[byref(f) for f in flags], byref(next_time))
        return (status, *(f.value for f in flags), next_time.value)

    def completed_integrator_step(self, no_set_prior=True):
        """fmi3CompletedIntegratorStep: (status, enterEventMode,
        terminateSimulation), the flags read as bytes."""
        enter, terminate = c_uint8(0xAA), c_uint8(0xAA)
        status = self.lib.fmi3CompletedIntegratorStep(self.c, no_set_prior, byref(enter), byref(terminate))
        return status, enter.value, terminate.value

    def set_time(self, t):
        return self.lib.fmi3SetTime(self.c, t)

    def set_continuous_states(self, values):
        values = list(values)
        return self.lib.fmi3SetContinuousStates(self.c, array(c_double, values), len(values))

    def _vector(self, function, n):
        out = (c_double * max(n, 1))(*([float("nan")] * max(n, 1)))
        status = getattr(self.lib, function)(self.c, out, n)
        return status, list(out[:n])

    def continuous_states(self, n=NX):
        return self._vector("fmi3GetContinuousStates", n)

    def derivatives(self, n=NX):
        return self._vector("fmi3GetContinuousStateDerivatives", n)

    def event_indicators(self, n=NZ):
        return self._vector("fmi3GetEventIndicators", n)

    def nominals(self, n=NX):
        return self._vector("fmi3GetNominalsOfContinuousStates", n)

    def number_of(self, what):
        """fmi3GetNumberOf{what} (ContinuousStates, EventIndicators): (status, n)."""
        n = c_size_t(12345)
        status = getattr(self.lib, f"fmi3GetNumberOf{what}")(self.c, byref(n))
        return status, n.value

    def euler_step(self, h):
        """One explicit Euler step of size h in Continuous-Time Mode,
        completed: (status, enterEventMode, terminateSimulation) of
        fmi3CompletedIntegratorStep."""
        status, x = self.continuous_states()
        assert status == OK, self.log.last()
        status, dx = self.derivatives()
        assert status == OK, self.log.last()
        assert self.set_time(self.time + h) == OK, self.log.last()
        self.time += h
        assert self.set_continuous_states([a + h * b for a, b in zip(x, dx)]) == OK, self.log.last()
        return self.completed_integrator_step()

    # -------------------------------------------------------------- FMU states

    def get_state(self, reuse=None):
        s = fmi3FMUState(reuse)
        status = self.lib.fmi3GetFMUState(self.c, byref(s))
        return status, s

    def free_state(self, state):
        return self.lib.fmi3FreeFMUState(self.c, byref(state))

    def serialize(self, state) -> bytes:
        size = c_size_t()
        assert self.lib.fmi3SerializedFMUStateSize(self.c, state, byref(size)) == OK, self.log.last()
        buf = (ctypes.c_char * size.value)()
        assert self.lib.fmi3SerializeFMUState(self.c, state, buf, size.value) == OK, self.log.last()
        return bytes(buf)

    def deserialize(self, data: bytes):
        s = fmi3FMUState()
        buf = (ctypes.c_char * max(len(data), 1)).from_buffer_copy(data or b"\0")
        status = self.lib.fmi3DeserializeFMUState(self.c, buf, len(data), byref(s))
        return status, s

    def snapshot(self) -> bytes:
        """The serialized bytes of the current state (everything an FMU state
        holds), without leaving an FMU state behind."""
        status, state = self.get_state()
        assert status == OK, self.log.last()
        data = self.serialize(state)
        assert self.free_state(state) == OK
        return data

    def machine_state(self) -> str:
        """The FMI 3.0 state, read without changing anything:
        fmi3ExitConfigurationMode is allowed in Configuration Mode only, so
        its refusal names any other state (in Configuration Mode it
        succeeds, and the instance goes back into it)."""
        before = len(self.log.messages)
        status = self.lib.fmi3ExitConfigurationMode(self.c)
        if status == OK:
            assert self.lib.fmi3EnterConfigurationMode(self.c) == OK, self.log.last()
            return "Configuration Mode"
        assert status == ERROR, status
        message = self.log.since(before)[-1][2]
        m = re.fullmatch(r"fmi3ExitConfigurationMode: not allowed in state (.+)", message)
        assert m, message
        return m.group(1)
