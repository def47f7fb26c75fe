"""Synthetic laboratory records from an independent scipy reference (the equations of tests/reference_history.py,
in the laboratory's parameters at m2 = 0, written from PHYSICS.md and not from the package's code):

    mu(v, theta) = mu0 + a ln(v/V0) + b ln(V0 theta/Dc)       (rate and state, = paper eq. 1 with A = a, m1 = b - a)
    dmu/dt = k (v_lp - v)   [k = K/(M g), 1/m]
    aging: dtheta/dt = 1 - v theta/Dc;   slip: dtheta/dt = -(v theta/Dc) ln(v theta/Dc)

from steady sliding at the first segment's velocity, integrated in (mu, ln theta) with Radau at rtol 1e-10, the
values at the asked times from the solver's own steps (t_eval), the load-point displacement exactly."""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp


def record_reference(a, b, Dc, mu0, k, velocities, durations, t, law="aging", V0=1e-6, rtol=1e-10):
    """(mu at the times ``t`` [s] (sorted, from 0), load-point displacement at ``t`` [m]) for the history of
    ``velocities`` [m/s] held for ``durations`` [s]."""
    t = np.asarray(t, dtype=float)

    def velocity(mu, lth):
        return V0 * np.exp((mu - mu0 - b * (np.log(V0 / Dc) + lth)) / a)

    def rhs(_, y, v_lp):
        v = velocity(y[0], y[1])
        E = v * np.exp(y[1]) / Dc
        dth = 1.0 - E if law == "aging" else -E * np.log(E)
        return [k * (v_lp - v), dth / np.exp(y[1])]

    v1 = velocities[0]
    y = np.array([mu0 + (a - b) * np.log(v1 / V0), np.log(Dc / v1)])
    mu, disp = np.empty(t.size), np.empty(t.size)
    start, x0 = 0.0, 0.0
    for s, (v_lp, T) in enumerate(zip(velocities, durations)):
        end = start + T
        last = s == len(velocities) - 1
        pick = np.flatnonzero((t >= start) & ((t < end) if not last else (t <= end * (1 + 1e-12))))
        tau = np.clip(t[pick] - start, 0.0, T)
        if tau.size == 0 or tau[-1] < T:
            tau = np.append(tau, T)  # the segment's end: where the next one starts
        sol = solve_ivp(rhs, (0.0, T), y, method="Radau", rtol=rtol, atol=[1e-14, 1e-12], args=(v_lp,),
                        t_eval=tau, first_step=min(T, 1e-6 * Dc / max(v_lp, v1)))
        assert sol.success, sol.message
        mu[pick] = sol.y[0, :pick.size]
        disp[pick] = x0 + v_lp * (t[pick] - start)
        y = sol.y[:, -1]
        start, x0 = end, x0 + v_lp * T
    return mu, disp
