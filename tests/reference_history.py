"""Independent scipy reference of the quasi-static spring-slider under a piecewise load history (PHYSICS.md 1 and 7),
in physical units and the paper's variables, written from the equations and not from the package's code:

    mu(v, phi) = mu_d(D0/phi) + A ln(v phi/D0),   mu_d(v) = m0 - m1 ln(v/V0) + m2 ln(v/V0)^2     (paper eq. 1, 6)
    => v = (D0/phi) exp((mu - mu_d(D0/phi))/A)
    dmu/dt = k_lab (v_lp - v),   k_lab = K/(M g) [1/m]
    aging: dphi/dt = 1 - v phi/D0;   slip: dphi/dt = -(v phi/D0) ln(v phi/D0)

integrated in (mu, ln phi) with Radau at rtol 1e-10 segment by segment; peaks located by solve_ivp's events
(dmu/dt = 0, falling). With inertia (Newton's law, PHYSICS.md 7): inertial_reference_at in t, and
inertial_reference_mapped in a plunge-resolving time for stiff springs and fast slides."""

from __future__ import annotations

import numpy as np
from scipy.integrate import Radau, solve_ivp

G = 9.81


def history_reference(A, m1, m2, D0, K_over_M, V, segments, law="aging", m0=0.3, V0=1e-6, stretch=0.0, rtol=1e-10):
    """Per segment (mu_start, mu_end, mu_peak) of the history ``segments`` (dicts with V_ratio and duration [s] or
    displacement [m]), from steady sliding at the first segment's velocity with the spring stretched by ``stretch``
    [m] beyond it; also the final (v, phi)."""
    k_lab = K_over_M / G

    def mu_d(v):
        lv = np.log(v / V0)
        return m0 - m1 * lv + m2 * lv * lv

    def velocity(mu, lphi):
        phi = np.exp(lphi)
        return D0 / phi * np.exp((mu - mu_d(D0 / phi)) / A)

    def rhs(t, y, v_lp):
        v = velocity(y[0], y[1])
        E = v * np.exp(y[1]) / D0
        dphi = 1.0 - E if law == "aging" else -E * np.log(E)
        return [k_lab * (v_lp - v), dphi / np.exp(y[1])]

    segments = [{"V_ratio": 0.0, "duration": s["hold"]} if "hold" in s else s for s in segments]
    v1 = segments[0]["V_ratio"] * V
    y = np.array([mu_d(v1) + k_lab * stretch, np.log(D0 / v1)])
    out = []
    for seg in segments:
        v_lp = seg["V_ratio"] * V
        T = seg["duration"] if "duration" in seg else seg["displacement"] / v_lp
        peak = lambda t, y, v_lp: k_lab * (v_lp - velocity(y[0], y[1]))  # noqa: E731
        peak.direction = -1
        sol = solve_ivp(rhs, (0.0, T), y, method="Radau", rtol=rtol, atol=[1e-14, 1e-12], args=(v_lp,),
                        events=peak, first_step=min(T, 1e-6 * D0 / max(v_lp, V)))
        assert sol.success, sol.message
        peaks = [ye[0] for ye in sol.y_events[0]]
        mu_start = y[0]
        y = sol.y[:, -1]
        out.append({"mu_start": mu_start, "mu_end": y[0], "mu_peak": max([mu_start, y[0], *peaks])})
    return out, (velocity(y[0], y[1]), np.exp(y[1]))


def history_reference_at(A, m1, m2, D0, K_over_M, velocities, durations, times, law="aging", m0=0.3, V0=1e-6,
                         stretch=0.0, g=G, rtol=1e-10, method="Radau"):
    """mu at the sorted ``times`` [s] from the start of the history of load-point ``velocities`` [m/s] held for
    ``durations`` [s], from steady sliding at velocities[0] with the spring stretched by ``stretch`` [m]. Each
    segment is integrated in pieces that end at its sample times (no interpolation: every value is a step's end
    at ``rtol``); a sample on a segment boundary takes the earlier segment's end."""
    k_lab = K_over_M / g

    def mu_d(v):
        lv = np.log(v / V0)
        return m0 - m1 * lv + m2 * lv * lv

    def rhs(t, y, v_lp):
        phi = np.exp(y[1])
        v = D0 / phi * np.exp((y[0] - mu_d(D0 / phi)) / A)
        E = v * phi / D0
        dphi = 1.0 - E if law == "aging" else -E * np.log(E)
        return [k_lab * (v_lp - v), dphi / phi]

    times = np.asarray(times, float)
    y = np.array([mu_d(velocities[0]) + k_lab * stretch, np.log(D0 / velocities[0])])
    out = np.full(times.size, np.nan)
    ends = np.cumsum(durations)
    i, start = 0, 0.0
    for j, (v_lp, end) in enumerate(zip(velocities, ends)):
        last = j == len(durations) - 1
        stops = [tt for tt in times[(times >= start) & ((times <= end) | last)] if tt > start]
        while i < times.size and times[i] <= start:
            out[i] = y[0]
            i += 1
        t0 = start
        for stop in [*stops, end] if not stops or stops[-1] < end else stops:
            if stop > t0:
                sol = solve_ivp(rhs, (t0, stop), y, method=method, rtol=rtol, atol=[1e-14, 1e-12], args=(v_lp,),
                                first_step=min(stop - t0, 1e-6 * D0 / max(v_lp, velocities[0])))
                assert sol.success, sol.message
                y, t0 = sol.y[:, -1], stop
            while i < times.size and times[i] <= t0:
                out[i] = y[0]
                i += 1
        start = end
    return out


def inertial_reference_at(A, m1, m2, D0, K_over_M, velocities, durations, times, m0=0.3, V0=1e-6, g=G, stretch=0.0,
                          rtol=1e-10):
    """The history with inertia (PHYSICS.md 7: M x'' = K (x_lp - x) - M g mu(x', phi), aging law), in physical
    units: the spring's force per normal load f = K (x_lp - x)/(M g) (the friction a laboratory measures), the
    slider's ln v and ln phi,

        df/dt = (K/(M g)) (v_lp - v),   d ln v/dt = g (f - mu(v, phi))/v,   dphi/dt = 1 - v phi/D0,
        mu(v, phi) = mu_d(D0/phi) + A ln(v phi/D0),

    from steady sliding at velocities[0] (v, phi = D0/v, f = mu_d(v) + k_lab ``stretch``), integrated with Radau
    at ``rtol`` in pieces that end at the sample times and segment ends. Returns (f at ``times``, per segment
    (f_start, f_end, f_peak) with the peaks from events df/dt = 0, falling)."""
    k_lab = K_over_M / g

    def mu_d(v):
        lv = np.log(v / V0)
        return m0 - m1 * lv + m2 * lv * lv

    def rhs(t, y, v_lp):
        f, lv, lphi = y
        v, phi = np.exp(lv), np.exp(lphi)
        mu = mu_d(D0 / phi) + A * (lv + lphi - np.log(D0))
        return [k_lab * (v_lp - v), g * (f - mu) / v, (1.0 - v * phi / D0) / phi]

    def rising(t, y, v_lp):
        return v_lp - np.exp(y[1])

    rising.direction = -1
    times = np.asarray(times, float)
    v1 = velocities[0]
    y = np.array([mu_d(v1) + k_lab * stretch, np.log(v1), np.log(D0 / v1)])
    out, segs = np.full(times.size, np.nan), []
    i, start = 0, 0.0
    for v_lp, end in zip(velocities, np.cumsum(durations)):
        while i < times.size and times[i] <= start:
            out[i] = y[0]
            i += 1
        f_start, peak, t0 = y[0], max(y[0], -np.inf), start
        for stop in [*times[(times > start) & (times < end)], end]:
            sol = solve_ivp(rhs, (t0, stop), y, method="Radau", rtol=rtol, atol=[1e-14, 1e-10, 1e-10], args=(v_lp,),
                            events=rising, first_step=min(stop - t0, 1e-9))
            assert sol.success, sol.message
            peak = max([peak, *(ye[0] for ye in sol.y_events[0])])
            y, t0 = sol.y[:, -1], stop
            while i < times.size and times[i] <= t0:
                out[i] = y[0]
                i += 1
        segs.append((f_start, y[0], max(peak, y[0])))
        start = end
    return out, segs


NU = 1e-6
"""Weight [s] of the reference's time map dt/dtheta = 1/(1 + NU R (1 + P^2)) (inertial_reference_mapped)."""


def inertial_reference_mapped(A, m1, m2, D0, K_over_M, velocities, durations, times, m0=0.3, V0=1e-6, g=G,
                              rtol=1e-10):
    """The history with inertia as :func:`inertial_reference_at`, for stiff springs and fast slides (k G large), where
    an inertial swing ends in a plunge that Radau cannot follow in t ("step size less than spacing"). The state
    carries the inertial term itself, P = (f - mu)/A (so that it keeps its own relative accuracy when tiny), with
    ln v = (f - mu_d(D0/phi))/A - ln(phi/D0) - P and R = g A/v:

        df/dt = k_lab (v_lp - v),   d ln phi/dt = 1/phi - v/D0,
        dP/dt = (df/dt)/A - ((m1 - 2 m2 L)/A + 1) d ln phi/dt - R P,   L = ln(D0/(phi V0)),

    integrated by scipy's Radau class stepped by hand, with its analytic Jacobian, in a time theta with dt/dtheta =
    1/(1 + NU R (1 + P^2)) (t a fourth state; the map of tests/reference_inertial.py): theta = t up to rounding
    where 1/R >> NU, and where not (a plunge, or a slider at rest: R up to 1e30/s) P relaxes at ~1/(NU (1 + P^2))
    per unit theta, smoothly. A sample time or a segment's end inside a step is reached by a plain Radau run in t
    (no map) from the step's start. Returns f at ``times`` (sorted, [s])."""
    k_lab = K_over_M / g
    l0 = np.log(D0 / V0)

    def parts(y):
        f, lphi, P = y[0], y[1], y[2]
        L = l0 - lphi
        lv = (f - (m0 - m1 * L + m2 * L * L)) / A - (lphi - np.log(D0)) - P
        return f, lphi, P, L, lv

    def rates(y, v_lp):
        f, lphi, P, L, lv = parts(y)
        v = np.exp(lv)
        df = k_lab * (v_lp - v)
        dl = np.exp(-lphi) - v / D0
        inv_r = np.exp(lv) / (g * A)  # 1/R
        return df, dl, P, L, inv_r, (df / A - ((m1 - 2 * m2 * L) / A + 1.0) * dl)

    def rhs_t(t, y, v_lp):
        df, dl, P, L, inv_r, drive = rates(y, v_lp)
        return [df, dl, drive - P / inv_r]

    def rhs_theta(theta, y, v_lp):
        df, dl, P, L, inv_r, drive = rates(y, v_lp)
        W = inv_r / (inv_r + NU * (1.0 + P * P))  # 1/(1 + NU R (1 + P^2))
        RW = 1.0 / (inv_r + NU * (1.0 + P * P))
        return [W * df, W * dl, W * drive - P * RW, W]

    def jac_theta(theta, y, v_lp):
        """d(rhs_theta)/dy, analytic (finite differences fail where R is huge)."""
        f, lphi, P, L, lv = parts(y)
        v = np.exp(lv)
        df, dl, _, _, q, drive = rates(y, v_lp)
        dlv = np.array([1.0 / A, -(m1 - 2 * m2 * L) / A - 1.0, -1.0, 0.0])
        e_p = np.array([0.0, 0.0, 1.0, 0.0])
        d_df = -k_lab * v * dlv
        d_dl = -(v / D0) * dlv + np.array([0.0, -np.exp(-lphi), 0.0, 0.0])
        c = (m1 - 2 * m2 * L) / A + 1.0
        d_drive = d_df / A - c * d_dl - dl * np.array([0.0, 2 * m2 / A, 0.0, 0.0])
        D = q + NU * (1.0 + P * P)
        d_D = q * dlv + 2 * NU * P * e_p
        W, RW = q / D, 1.0 / D
        d_W = q * dlv / D - q * d_D / D**2
        d_RW = -d_D / D**2
        return np.array([d_W * df + W * d_df, d_W * dl + W * d_dl,
                         d_W * drive + W * d_drive - e_p * RW - P * d_RW, d_W])

    atol = [1e-14, 1e-12, 1e-14, 1e-14]
    v1 = velocities[0]
    L1 = l0 - np.log(D0 / v1)
    y = np.array([m0 - m1 * L1 + m2 * L1 * L1, np.log(D0 / v1), 0.0])
    times = np.asarray(times, float)
    out = np.full(times.size, np.nan)
    i, start = 0, 0.0
    for v_lp, end in zip(velocities, np.cumsum(durations)):
        stops = [*times[(times > start) & (times < end)], end]
        while i < times.size and times[i] <= start:
            out[i] = y[0]
            i += 1
        solver = Radau(lambda th, z, v=v_lp: rhs_theta(th, z, v), 0.0, np.append(y, start), np.inf, rtol=rtol,
                       atol=atol, first_step=1e-9, jac=lambda th, z, v=v_lp: jac_theta(th, z, v))
        for stop in stops:
            while True:
                prev = solver.y.copy()
                if prev[3] >= stop:
                    break
                solver.step()
                assert solver.status != "failed", (solver.status, solver.t, solver.y)
                if solver.status == "running" and solver.step_size < 1e-10 * solver.t:
                    # theta grew huge while the slider stood (R huge): restart it at 0, so that it can resolve
                    # the small steps to come (the system is autonomous in theta)
                    solver = Radau(lambda th, z, v=v_lp: rhs_theta(th, z, v), 0.0, solver.y.copy(), np.inf,
                                   rtol=rtol, atol=atol, first_step=solver.step_size,
                                   jac=lambda th, z, v=v_lp: jac_theta(th, z, v))
                if solver.y[3] > stop:  # the stop is inside this step: plain Radau in t from its start
                    sol = solve_ivp(rhs_t, (prev[3], stop), prev[:3], method="Radau", rtol=rtol, atol=atol[:3],
                                    args=(v_lp,), first_step=min(stop - prev[3], 1e-9))
                    assert sol.success, sol.message
                    solver = Radau(lambda th, z, v=v_lp: rhs_theta(th, z, v), 0.0, np.append(sol.y[:, -1], stop),
                                   np.inf, rtol=rtol, atol=atol, first_step=1e-9,
                                   jac=lambda th, z, v=v_lp: jac_theta(th, z, v))
                    break
            while i < times.size and times[i] <= solver.y[3]:
                out[i] = solver.y[0]
                i += 1
        y, start = solver.y[:3].copy(), end
    return out
