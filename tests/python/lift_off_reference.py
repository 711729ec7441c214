"""An independent reference for the unilateral tire: the quarter car of
Eq. (1) written out here (not taken from tdvass), integrated by scipy's
DOP853 with event location for every lift-off and touchdown, the squares of
BA, SDD and TDD integrated as quadrature states.

Only CS and PVASS (no delay), on a harmonic road or on a piecewise-linear
road given by samples."""

import numpy as np
from scipy.integrate import solve_ivp

STANDARD_GRAVITY = 9.80665
TABLE_1 = dict(m_s=345.0, m_h=4.05, m_t=40.5, k_s=16000.0, k_h=6444.0,
               k_t=190000.0, c_s=1500.0, c_h=348.0)


def plant(variant, p=TABLE_1):
    """A (contact), the road column e, and the static load W for the state
    [x_s, v_s, x_h, v_h, x_t, v_t] (CS: the absorber rows stay at rest)."""
    m_s, m_h, m_t = p["m_s"], p["m_h"], p["m_t"]
    k_s, k_h, k_t, c_s, c_h = p["k_s"], p["k_h"], p["k_t"], p["c_s"], p["c_h"]
    a = np.zeros((6, 6))
    a[0, 1] = a[2, 3] = a[4, 5] = 1.0
    if variant == "cs":
        # m_s x_s'' = -k_s (x_s - x_t) - c_s (v_s - v_t)
        a[1, 0], a[1, 1], a[1, 4], a[1, 5] = -k_s / m_s, -c_s / m_s, k_s / m_s, c_s / m_s
        # m_t x_t'' = k_s (x_s - x_t) + c_s (v_s - v_t) + F_tire
        a[5, 0], a[5, 1] = k_s / m_t, c_s / m_t
        a[5, 4], a[5, 5] = -(k_s + k_t) / m_t, -c_s / m_t
        a[2, 3] = 0.0
        weight = (m_s + m_t) * STANDARD_GRAVITY
    else:
        # body on k_s, c_s to the absorber; absorber on k_h, c_h to the wheel
        a[1, 0], a[1, 1], a[1, 2], a[1, 3] = -k_s / m_s, -c_s / m_s, k_s / m_s, c_s / m_s
        a[3, 0], a[3, 1] = k_s / m_h, c_s / m_h
        a[3, 2], a[3, 3] = -(k_s + k_h) / m_h, -(c_s + c_h) / m_h
        a[3, 4], a[3, 5] = k_h / m_h, c_h / m_h
        a[5, 2], a[5, 3] = k_h / m_t, c_h / m_t
        a[5, 4], a[5, 5] = -(k_h + k_t) / m_t, -c_h / m_t
        weight = (m_s + m_h + m_t) * STANDARD_GRAVITY
    e = np.zeros(6)
    e[5] = k_t / m_t
    return a, e, weight, k_t


def reference(variant, road, duration, breakpoints=(), rtol=1e-12):
    """RMS of BA, SDD, TDD over [0, duration] from rest, the flight time and
    the number of lift-offs, with a unilateral tire. `road(t)` gives x_g;
    `breakpoints` are the times where its slope jumps (integration restarts
    there)."""
    a, e, weight, k_t = plant(variant)
    limit = weight / k_t
    flight_a = a.copy()
    flight_a[5, 4] += e[5]  # no tire spring in flight

    def rhs(t, y, flying):
        x = y[:6]
        xg = road(t)
        if flying:
            dx = flight_a @ x - e * limit
        else:
            dx = a @ x + e * xg
        ba = a[1] @ x
        sdd = x[0] - x[4]
        tdd = x[4] - xg
        return np.concatenate([dx, [ba * ba, sdd * sdd, tdd * tdd]])

    def margin(t, y, flying):
        # W/k_t - TDD: falls through 0 at a lift-off, rises at a touchdown
        return limit - (y[4] - road(t))

    cuts = sorted({0.0, duration, *[b for b in breakpoints if 0.0 < b < duration]})
    y = np.zeros(9)
    flying = False
    flight_start = None
    flight_time = 0.0
    lift_offs = 0
    for lo, hi in zip(cuts[:-1], cuts[1:]):
        t = lo
        while t < hi:
            event = lambda s, z, f=flying: margin(s, z, f)
            event.terminal = True
            event.direction = 1.0 if flying else -1.0
            sol = solve_ivp(rhs, (t, hi), y, method="DOP853", rtol=rtol,
                            atol=1e-14, events=event, args=(flying,))
            if not sol.success:
                raise RuntimeError(sol.message)
            if sol.t_events[0].size and sol.t_events[0][0] < hi:
                t = sol.t_events[0][0]
                y = sol.y_events[0][0]
                if flying:
                    flight_time += t - flight_start
                else:
                    lift_offs += 1
                    flight_start = t
                flying = not flying
            else:
                t = hi
                y = sol.y[:, -1]
    if flying:
        flight_time += duration - flight_start
    rms = np.sqrt(y[6:] / duration)
    return dict(rms_ba=rms[0], rms_sdd=rms[1], rms_tdd=rms[2],
                contact_loss_time=flight_time, lift_off_count=lift_offs)


def iso8608_samples(road_class_gq, speed, duration, interval, seed):
    """An ISO 8608 road as samples every `interval` s: the filtered white
    noise dx_g/dt = -2 pi f0 x_g + 2 pi n0 sqrt(Gq u) w(t), f0 = 0.1 Hz,
    n0 = 0.1 1/m, integrated exactly over each interval with the noise held
    (variance 1/interval)."""
    f0, n0 = 0.1, 0.1
    rate = 2 * np.pi * f0
    gain = 2 * np.pi * n0 * np.sqrt(road_class_gq * speed)
    rng = np.random.default_rng(seed)
    n = int(round(duration / interval))
    decay = np.exp(-rate * interval)
    x = np.zeros(n + 1)
    for i in range(n):
        w = rng.standard_normal() / np.sqrt(interval)
        x[i + 1] = x[i] * decay + gain * w * (1 - decay) / rate
    return np.arange(n + 1) * interval, x
