"""A Model Exchange master of the tests' own, for either FMI version: it
instantiates the FMU through fmpy's low-level classes, and offers the calls a
solver makes (derivatives at a time and states, event indicators, completed
steps, the Jacobian from the FMU's directional derivatives) to the
integration loops of the tests: explicit Runge–Kutta at a fixed step, and
scipy's implicit solvers."""

from __future__ import annotations

from ctypes import c_double

import fmpy
import numpy as np
from fmpy import read_model_description


class ModelExchangeMaster:
    """One Model Exchange instance of `fmu` with `start_values`, in
    Continuous-Time Mode at the start time 0."""

    def __init__(self, fmu, start_values, unzipdir=None, name="master"):
        self.md = read_model_description(str(fmu))
        self.fmi3 = self.md.fmiVersion.startswith("3")
        unzipdir = unzipdir or fmpy.extract(str(fmu))
        by_name = {v.name: v for v in self.md.modelVariables}
        self.by_name = by_name
        if self.fmi3:
            from fmpy.fmi3 import FMU3Model

            self.fmu = FMU3Model(guid=self.md.instantiationToken, unzipDirectory=unzipdir,
                                 modelIdentifier=self.md.modelExchange.modelIdentifier, instanceName=name)
            self.fmu.instantiate()
        else:
            from fmpy.fmi2 import FMU2Model

            self.fmu = FMU2Model(guid=self.md.guid, unzipDirectory=unzipdir,
                                 modelIdentifier=self.md.modelExchange.modelIdentifier, instanceName=name)
            self.fmu.instantiate()
            self.fmu.setupExperiment(startTime=0.0)
        for key, value in start_values.items():
            self.set(key, value)
        if self.fmi3:
            self.fmu.enterInitializationMode(startTime=0.0)
        else:
            self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self.event_update()
        self.fmu.enterContinuousTimeMode()
        derivatives = self.md.derivatives
        self.n = len(derivatives)
        self.state_vrs = [d.variable.derivative.valueReference for d in derivatives]
        self.derivative_vrs = [d.variable.valueReference for d in derivatives]
        self.buffer = (c_double * self.n)()
        self.indicator_buffer = (c_double * 1)()
        self.x = self.states()
        self.t = 0.0

    def set(self, name, value):
        v = self.by_name[name]
        if v.type in ("Real", "Float64"):
            (self.fmu.setFloat64 if self.fmi3 else self.fmu.setReal)([v.valueReference], [float(value)])
        else:
            (self.fmu.setInt64 if self.fmi3 else self.fmu.setInteger)([v.valueReference], [int(value)])

    def event_update(self):
        """The event iteration; returns whether the FMU asked for a restart
        of the integrator (valuesOfContinuousStatesChanged)."""
        restart = False
        while True:
            update = self.fmu.updateDiscreteStates() if self.fmi3 else self.fmu.newDiscreteStates()
            # (needed, terminate, nominals changed, values changed, ...)
            restart |= bool(update[3])
            if not update[0]:
                return restart

    def states(self):
        self.fmu.getContinuousStates(self.buffer, self.n)
        return np.array(self.buffer[:])

    def set_point(self, t, x):
        self.fmu.setTime(t)
        self.fmu.setContinuousStates((c_double * self.n)(*x), self.n)

    def derivatives(self, t, x):
        self.set_point(t, x)
        if self.fmi3:
            self.fmu.getContinuousStateDerivatives(self.buffer, self.n)
        else:
            self.fmu.getDerivatives(self.buffer, self.n)
        return np.array(self.buffer[:])

    def indicator(self, t, x):
        self.set_point(t, x)
        self.fmu.getEventIndicators(self.indicator_buffer, 1)
        return self.indicator_buffer[0]

    def complete(self):
        self.fmu.completedIntegratorStep()

    def event(self, t, x):
        """Event Mode at (t, x) and back to Continuous-Time Mode; returns
        whether the FMU asked for a restart of the integrator."""
        self.set_point(t, x)
        self.fmu.enterEventMode()
        restart = self.event_update()
        self.fmu.enterContinuousTimeMode()
        return restart

    def save(self):
        return self.fmu.getFMUState() if self.fmi3 else self.fmu.getFMUstate()

    def restore(self, state):
        (self.fmu.setFMUState if self.fmi3 else self.fmu.setFMUstate)(state)

    def release(self, state):
        (self.fmu.freeFMUState if self.fmi3 else self.fmu.freeFMUstate)(state)

    def read(self, name):
        v = self.by_name[name]
        vr = [v.valueReference]
        if v.type in ("Real", "Float64"):
            return (self.fmu.getFloat64 if self.fmi3 else self.fmu.getReal)(vr)[0]
        return (self.fmu.getInt32 if self.fmi3 else self.fmu.getInteger)(vr)[0]

    def partials(self, unknowns, knowns):
        """The matrix ∂unknowns/∂knowns (value references) from the FMU's
        directional derivatives, one column per known."""
        columns = []
        for j in range(len(knowns)):
            seed = [0.0] * len(knowns)
            seed[j] = 1.0
            columns.append(self.fmu.getDirectionalDerivative(unknowns, knowns, seed))
        return np.array(columns).T

    def jacobian(self, t, x):
        """∂der/∂x at (t, x) (nothing recorded in the delay history)."""
        self.set_point(t, x)
        return self.partials(self.derivative_vrs, self.state_vrs)

    def free(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


# Explicit Runge–Kutta methods: (c, a, b).
RK4 = ([0.0, 0.5, 0.5, 1.0], [[], [0.5], [0.0, 0.5], [0.0, 0.0, 1.0]], [1 / 6, 1 / 3, 1 / 3, 1 / 6])
HEUN = ([0.0, 1.0], [[], [1.0]], [0.5, 0.5])


def explicit(master: ModelExchangeMaster, method, t_end, h, complete=True):
    """Integrates `master` to `t_end` at the fixed step `h` (no events),
    calling CompletedIntegratorStep after every step when `complete`."""
    c, a, b = method
    t0, x = master.t, master.x
    steps = int(round((t_end - t0) / h))
    for n in range(steps):
        t = t0 + n * h
        k = []
        for i, ci in enumerate(c):
            stage = x + h * sum((aij * kj for aij, kj in zip(a[i], k)), np.zeros_like(x))
            k.append(master.derivatives(t + ci * h, stage))
        x = x + h * sum(bi * ki for bi, ki in zip(b, k))
        master.set_point(t0 + (n + 1) * h, x)
        if complete:
            master.complete()
    master.t, master.x = t0 + steps * h, x
    return x
