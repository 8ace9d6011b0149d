"""Slow, straightforward reference of the rotor equations, written independently
of ``simulator._kernels``: SI units and time t (not X = x/c, τ = Ωt), the
generator stiffness built by rotating diag(k̄(1+ρ), k̄(1−ρ)), the oil film from
MODEL.md's literal atan/sign formula for α, and the ``pin`` constraint solved
through the Lagrangian mass matrix of (x4, y4, φ) instead of the closed form.

State (SI): [x1, y1, x2, y2, x4, y4, x5, y5, x6, y6, φ, and their time derivatives].
"""
from __future__ import annotations

import math

import numpy as np


def capone_literal(X, Y, Xd, Yd):
    """MODEL.md section 4 with α from atan and sign (valid away from 0/0)."""
    a = X - 2 * Yd
    b = Y + 2 * Xd
    alpha = math.atan(b / a) - math.pi / 2 * np.sign(b / a) - math.pi / 2 * np.sign(b)
    ca, sa = math.cos(alpha), math.sin(alpha)
    h = 1 - X**2 - Y**2
    G = 2 / math.sqrt(h) * (math.pi / 2 + math.atan((Y * ca - X * sa) / math.sqrt(h)))
    V = (2 + (Y * ca - X * sa) * G) / h
    S = (X * ca + Y * sa) / (1 - (X * ca + Y * sa) ** 2)
    pre = -math.sqrt(a**2 + b**2) / h
    return np.array([pre * (3 * X * V - sa * G - 2 * ca * S), pre * (3 * Y * V + ca * G - 2 * sa * S)])


def ocvirk_static(eps):
    """Ocvirk's short-bearing static load |f| and attitude angle ψ (rad)."""
    f = eps / (1 - eps**2) ** 2 * math.sqrt(math.pi**2 * (1 - eps**2) + 16 * eps**2)
    psi = math.atan(math.pi * math.sqrt(1 - eps**2) / (4 * eps))
    return f, psi


class ReferenceRotor:
    """Equations of motion in SI units for a plant dict (``Plant.to_dict()``)."""

    def __init__(self, plant: dict, speed_rpm, misalignment, unbalance, mechanism="pin",
                 unbalance_phase=0.0, exciter_unbalance=0.0, exciter_phase=0.0, offset_angle=0.0):
        self.p = plant
        self.w = speed_rpm * math.pi / 30
        c = plant["clearance_m"]
        self.c = c
        self.delta = misalignment * c
        self.a1 = unbalance * c
        self.a2 = exciter_unbalance * c
        self.th1, self.th2, self.phi0 = unbalance_phase, exciter_phase, offset_angle
        self.mech = "aligned" if misalignment == 0 else mechanism
        R = np.asarray(plant["bearing_radius_m"])
        L = np.asarray(plant["bearing_length_m"])
        self.sb = plant["viscosity_pa_s"] * self.w * R * L**3 / (4 * c**2)
        self.off = np.asarray(plant["bearing_offset_m"], dtype=float)

    def K1(self, t):
        th = self.w * t + self.p["stiff_axis_angle_rad"]
        rot = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
        kb, rho = self.p["generator_stiffness_n_m"], self.p["asymmetry"]
        return rot @ np.diag([kb * (1 + rho), kb * (1 - rho)]) @ rot.T

    def bearing(self, b, r, v):
        rel = r - self.off[b]
        if self.p["bearing_model"] == "linear":
            return -self.p["linear_bearing_stiffness_n_m"] * rel - self.p["linear_bearing_damping_n_s_m"] * v
        c, w = self.c, self.w
        return self.sb[b] * capone_literal(rel[0] / c, rel[1] / c, v[0] / (c * w), v[1] / (c * w))

    def node3(self, t, s):
        r4, v4 = s[4:6], s[15:17]
        if self.mech == "aligned":
            return r4.copy(), v4.copy()
        if self.mech == "pin":
            phi, phid = s[10], s[21]
        else:
            phi, phid = self.w * t + self.phi0, self.w
        er = np.array([math.cos(phi), math.sin(phi)])
        et = np.array([-math.sin(phi), math.cos(phi)])
        return r4 + self.delta * er, v4 + self.delta * phid * et

    def __call__(self, t, s):
        p = self.p
        m1, M1, m3 = p["journal1_mass_kg"], p["generator_mass_kg"], p["journal3_mass_kg"]
        m4, M2, m6 = p["journal4_mass_kg"], p["exciter_mass_kg"], p["journal6_mass_kg"]
        g = np.array([0.0, -p["gravity_m_s2"]])
        r1, r2, r4, r5, r6 = s[0:2], s[2:4], s[4:6], s[6:8], s[8:10]
        v1, v2, v4, v5, v6 = s[11:13], s[13:15], s[15:17], s[17:19], s[19:21]
        r3, v3 = self.node3(t, s)
        K = self.K1(t)
        k2 = p["exciter_stiffness_n_m"]
        w = self.w
        u1 = M1 * self.a1 * w**2 * np.array([math.cos(w * t + self.th1), math.sin(w * t + self.th1)])
        u2 = M2 * self.a2 * w**2 * np.array([math.cos(w * t + self.th2), math.sin(w * t + self.th2)])
        P1 = K @ (r2 - r1) + m1 * g + self.bearing(0, r1, v1)
        P2 = -K @ (r2 - r1) - K @ (r2 - r3) - p["generator_damping_n_s_m"] * v2 + M1 * g + u1
        P3 = K @ (r2 - r3) + m3 * g + self.bearing(1, r3, v3)
        P4 = k2 * (r5 - r4) + m4 * g + self.bearing(2, r4, v4)
        P5 = -k2 * (r5 - r4) - k2 * (r5 - r6) - p["exciter_damping_n_s_m"] * v5 + M2 * g + u2
        P6 = k2 * (r5 - r6) + m6 * g + self.bearing(3, r6, v6)
        acc = np.zeros(11)
        acc[0:2], acc[2:4], acc[6:8], acc[8:10] = P1 / m1, P2 / M1, P5 / M2, P6 / m6
        if self.mech == "pin":
            d = self.delta
            phi, phid = s[10], s[21]
            sp, cp = math.sin(phi), math.cos(phi)
            # Lagrange: M(q) [ẍ4, ÿ4, φ̈] = Q + velocity terms
            M = np.array([[m3 + m4, 0.0, -m3 * d * sp], [0.0, m3 + m4, m3 * d * cp],
                          [-m3 * d * sp, m3 * d * cp, m3 * d**2]])
            rhs = np.array([P3[0] + P4[0] + m3 * d * cp * phid**2,
                            P3[1] + P4[1] + m3 * d * sp * phid**2,
                            d * (P3 @ np.array([-sp, cp]))])
            sol = np.linalg.solve(M, rhs)
            acc[4:6], acc[10] = sol[:2], sol[2]
        elif self.mech == "rigid":
            phi = w * t + self.phi0
            acc[4:6] = (P3 + P4 + m3 * self.delta * w**2 * np.array([math.cos(phi), math.sin(phi)])) / (m3 + m4)
        else:
            acc[4:6] = (P3 + P4) / (m3 + m4)
        return np.concatenate([s[11:22], acc])

    # conversions between the kernel's non-dimensional state and SI
    def to_si(self, y):
        s = np.array(y, dtype=float).copy()
        s[:10] *= self.c
        s[11:21] *= self.c * self.w
        s[21] *= self.w
        return s

    def accel_to_nondim(self, ds):
        out = ds.copy()
        out[:10] /= self.c * self.w
        out[10] /= self.w
        out[11:21] /= self.c * self.w**2
        out[21] /= self.w**2
        return out
