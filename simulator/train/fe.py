"""Finite-element matrices of a shaft train: Timoshenko beams, disks, couplings.

Degrees of freedom: four per node, ``[x, y, θx, θy]`` — displacements and rotations about +x and +y
(right-handed, shaft along +z). The bending slopes are θy = ∂x/∂z and θx = −∂y/∂z. Elements are
built in slope form (each bending plane's standard beam matrices on (w, ∂w/∂z)) and turned to
rotations once by the signed permutation ``T`` (q_slope = T q).

The equations of motion are

    M q̈ + (C + Ω G + η K_s) q̇ + (K + η Ω K_circ + ρ-terms(t)) q = f_gravity + f_unbalance(t) + f_bearings,

with the element matrices of Friswell, Penny, Garvey & Lees, *Dynamics of Rotating Machines* (2010),
§5.4 (Timoshenko translational and rotary mass, gyroscopic, stiffness with Φ = 12EI/(κGAL²)) and
Cowper's (1966) shear coefficient κ of a hollow circular section. The asymmetric stiffness of an
element with rotating-frame stiffnesses EI(1 ± ρ) is, in the stationary frame,
K̄ ⊗ [[1 + ρ cos 2θ, ρ sin 2θ], [ρ sin 2θ, 1 − ρ cos 2θ]], θ = Ωt + θ0.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from .model import Train

DOF_PER_NODE = 4


def cowper_shear_coefficient(outer_diameter_m: float, inner_diameter_m: float, poisson: float) -> float:
    """Cowper's (1966) shear coefficient κ of a hollow circular section."""
    m2 = (inner_diameter_m / outer_diameter_m) ** 2
    a = (1.0 + m2) ** 2
    return 6.0 * (1.0 + poisson) * a / ((7.0 + 6.0 * poisson) * a + (20.0 + 12.0 * poisson) * m2)


def section(outer_diameter_m: float, inner_diameter_m: float) -> tuple[float, float]:
    """Area (m²) and diametral second moment of area (m⁴) of a hollow circular section."""
    area = math.pi / 4.0 * (outer_diameter_m**2 - inner_diameter_m**2)
    inertia = math.pi / 64.0 * (outer_diameter_m**4 - inner_diameter_m**4)
    return area, inertia


def plane_matrices(length_m: float, young_pa: float, shear_pa: float, density_kg_m3: float,
                   outer_diameter_m: float, inner_diameter_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stiffness, translational mass and rotary mass (per unit ρI) of one bending plane, dofs
    (w1, w1', w2, w2'), Timoshenko (Friswell et al. 2010, eqs. 5.90–5.95).

    Returns K (4, 4), M_t (4, 4), M_r (4, 4); the gyroscopic block is M_r with the polar 2I for I.
    """
    L = length_m
    area, inertia = section(outer_diameter_m, inner_diameter_m)
    nu = young_pa / (2.0 * shear_pa) - 1.0
    kappa = cowper_shear_coefficient(outer_diameter_m, inner_diameter_m, nu)
    phi = 12.0 * young_pa * inertia / (kappa * shear_pa * area * L**2)
    k = young_pa * inertia / ((1.0 + phi) * L**3)
    K = k * np.array([
        [12.0, 6 * L, -12.0, 6 * L],
        [6 * L, (4 + phi) * L**2, -6 * L, (2 - phi) * L**2],
        [-12.0, -6 * L, 12.0, -6 * L],
        [6 * L, (2 - phi) * L**2, -6 * L, (4 + phi) * L**2],
    ])
    m1 = 13 / 35 + 7 * phi / 10 + phi**2 / 3
    m2 = (11 / 210 + 11 * phi / 120 + phi**2 / 24) * L
    m3 = 9 / 70 + 3 * phi / 10 + phi**2 / 6
    m4 = (13 / 420 + 3 * phi / 40 + phi**2 / 24) * L
    m5 = (1 / 105 + phi / 60 + phi**2 / 120) * L**2
    m6 = (1 / 140 + phi / 60 + phi**2 / 120) * L**2
    Mt = density_kg_m3 * area * L / (1 + phi) ** 2 * np.array([
        [m1, m2, m3, -m4],
        [m2, m5, m4, -m6],
        [m3, m4, m1, -m2],
        [-m4, -m6, -m2, m5],
    ])
    r1 = 6 / 5
    r2 = (1 / 10 - phi / 2) * L
    r3 = (2 / 15 + phi / 6 + phi**2 / 3) * L**2
    r4 = (-1 / 30 - phi / 6 + phi**2 / 6) * L**2
    Mr = density_kg_m3 * inertia / ((1 + phi) ** 2 * L) * np.array([
        [r1, r2, -r1, r2],
        [r2, r3, -r2, r4],
        [-r1, -r2, r1, -r2],
        [r2, r4, -r2, r3],
    ])
    return K, Mt, Mr


# index of the x-plane (x, ∂x/∂z) and y-plane (y, ∂y/∂z) dofs of a two-node element in slope form
_XP = np.array([0, 2, 4, 6])
_YP = np.array([1, 3, 5, 7])


@dataclass(kw_only=True)
class TrainMatrices:
    """The train's equations of motion, shared by the full model (:class:`Assembly`, rotation dofs
    ``[x, y, θx, θy]`` per node) and its reductions (``reduced.Reduced``, the same matrices on a basis).

    ``K`` mean (non-rotating) shaft and coupling stiffness; ``K_cos``/``K_sin`` the asymmetric parts:
    K(t) = K + cos 2(Ωt)·K_cos + sin 2(Ωt)·K_sin (each rotor's stiff-axis angle is inside them);
    ``K_shaft`` the shafts' stiffness alone (internal damping), ``K_circ`` its circulatory partner
    (force −η·(K_shaft q̇ + Ω K_circ q)); ``G`` gyroscopic per rad/s of spin; ``C`` stationary damping
    (couplings and proportional damping); ``gravity_n`` the gravity load vector.
    """

    M: np.ndarray
    K: np.ndarray
    K_cos: np.ndarray
    K_sin: np.ndarray
    K_shaft: np.ndarray
    K_circ: np.ndarray
    G: np.ndarray
    C: np.ndarray
    gravity_n: np.ndarray

    def stiffness_at(self, spin_angle_rad: float) -> np.ndarray:
        """The stationary-frame stiffness with the rotors turned by ``spin_angle_rad`` from t = 0."""
        return self.K + math.cos(2 * spin_angle_rad) * self.K_cos + math.sin(2 * spin_angle_rad) * self.K_sin

    def mean_stiffness(self, speed_rad_s: float, internal_damping_s: float) -> np.ndarray:
        """K + η Ω K_circ: the shafts' and couplings' stiffness at spin Ω, asymmetry at its mean, no bearings."""
        return self.K + internal_damping_s * speed_rad_s * self.K_circ

    def damping(self, speed_rad_s: float, internal_damping_s: float) -> np.ndarray:
        """C + Ω G + η K_shaft: stationary, gyroscopic and internal damping at spin Ω, no bearings."""
        return self.C + speed_rad_s * self.G + internal_damping_s * self.K_shaft

    def projected(self, T: np.ndarray) -> dict[str, np.ndarray]:
        """Every matrix on the basis ``T`` (q = T p): Tᵀ A T, and the load Tᵀ f — keyword arguments of a
        subclass that holds them on that basis."""
        out = {f.name: T.T @ getattr(self, f.name) @ T for f in fields(TrainMatrices) if f.name != "gravity_n"}
        out["gravity_n"] = T.T @ self.gravity_n
        return out


@dataclass(kw_only=True)
class Assembly(TrainMatrices):
    """The train's finite-element matrices (n_dof = 4·n_nodes; :class:`TrainMatrices`), its nodes, bearings,
    unbalances and couplings."""

    train: Train
    node_z_m: np.ndarray
    node_rotor: np.ndarray
    rotor_nodes: list[np.ndarray]
    support_nodes: np.ndarray
    support_centres_m: np.ndarray
    bearings: list
    unbalance_nodes: np.ndarray
    unbalance_kg_m: np.ndarray
    unbalance_angle_rad: np.ndarray
    flexible: list[tuple[int, int, float, float, float, float, float]]
    coupling_nodes: list[tuple[int, int]]

    @property
    def n_nodes(self) -> int:
        return len(self.node_z_m)

    @property
    def n_dof(self) -> int:
        return DOF_PER_NODE * self.n_nodes

    def translation(self, axis: int) -> np.ndarray:
        """Rigid-body translation of the whole train along x (0) or y (1), unit metres."""
        v = np.zeros(self.n_dof)
        v[axis::DOF_PER_NODE] = 1.0
        return v


def _slope_to_rotation(n_dof: int) -> np.ndarray:
    """T with q_slope = T q: ∂x/∂z = θy, ∂y/∂z = −θx."""
    T = np.zeros((n_dof, n_dof))
    for k in range(0, n_dof, 4):
        T[k, k] = T[k + 1, k + 1] = 1.0
        T[k + 2, k + 3] = 1.0
        T[k + 3, k + 2] = -1.0
    return T


def assemble(train: Train) -> Assembly:
    """Build the train's global matrices and load vectors."""
    node_z: list[float] = []
    node_rotor: list[int] = []
    rotor_nodes: list[np.ndarray] = []
    coupling_nodes: list[tuple[int, int]] = []
    z0 = train.rotor_start_z_m()
    for i, r in enumerate(train.rotors):
        zs = z0[i] + r.station_z_m()
        if i > 0 and train.couplings[i - 1].kind == "rigid":
            first = rotor_nodes[-1][-1]
            nodes = np.concatenate([[first], np.arange(len(node_z), len(node_z) + r.n_stations - 1)])
            node_z += list(zs[1:])
            node_rotor += [i] * (r.n_stations - 1)
        else:
            nodes = np.arange(len(node_z), len(node_z) + r.n_stations)
            node_z += list(zs)
            node_rotor += [i] * r.n_stations
        if i > 0:
            coupling_nodes.append((int(rotor_nodes[-1][-1]), int(nodes[0])))
        rotor_nodes.append(nodes.astype(int))
    n = len(node_z)
    nd = DOF_PER_NODE * n
    M = np.zeros((nd, nd))
    K = np.zeros((nd, nd))
    Kc = np.zeros((nd, nd))
    Ks = np.zeros((nd, nd))
    G = np.zeros((nd, nd))
    C = np.zeros((nd, nd))
    Kcirc = np.zeros((nd, nd))
    for i, r in enumerate(train.rotors):
        mat = r.material
        c2, s2 = math.cos(2 * r.stiff_axis_rad), math.sin(2 * r.stiff_axis_rad)
        for k, e in enumerate(r.elements):
            a, b = rotor_nodes[i][k], rotor_nodes[i][k + 1]
            idx = np.concatenate([np.arange(4 * a, 4 * a + 4), np.arange(4 * b, 4 * b + 4)])
            kp, mt, mr = plane_matrices(e.length_m, mat.young_pa, mat.shear_pa, mat.density_kg_m3,
                                        e.outer_diameter_m, e.inner_diameter_m)
            me = np.zeros((8, 8))
            ke = np.zeros((8, 8))
            ge = np.zeros((8, 8))
            kce = np.zeros((8, 8))
            kse = np.zeros((8, 8))
            kcirc = np.zeros((8, 8))
            for p in (_XP, _YP):
                me[np.ix_(p, p)] = mt + mr
                ke[np.ix_(p, p)] = kp
            ge[np.ix_(_XP, _YP)] = 2.0 * mr
            ge[np.ix_(_YP, _XP)] = -2.0 * mr
            rho = e.asymmetry
            kce[np.ix_(_XP, _XP)] = rho * c2 * kp
            kce[np.ix_(_YP, _YP)] = -rho * c2 * kp
            kce[np.ix_(_XP, _YP)] = rho * s2 * kp
            kce[np.ix_(_YP, _XP)] = rho * s2 * kp
            # sin 2θ part: cos(2Ωt + 2θ0) = cos2Ωt c2 − sin2Ωt s2, sin(2Ωt + 2θ0) = sin2Ωt c2 + cos2Ωt s2
            kse[np.ix_(_XP, _XP)] = -rho * s2 * kp
            kse[np.ix_(_YP, _YP)] = rho * s2 * kp
            kse[np.ix_(_XP, _YP)] = rho * c2 * kp
            kse[np.ix_(_YP, _XP)] = rho * c2 * kp
            kcirc[np.ix_(_XP, _YP)] = kp
            kcirc[np.ix_(_YP, _XP)] = -kp
            ix = np.ix_(idx, idx)
            M[ix] += me
            K[ix] += ke
            G[ix] += ge
            Kc[ix] += kce
            Ks[ix] += kse
            Kcirc[ix] += kcirc
        for d in r.disks:
            j = 4 * rotor_nodes[i][d.station]
            M[j, j] += d.mass_kg
            M[j + 1, j + 1] += d.mass_kg
            M[j + 2, j + 2] += d.transverse_kg_m2
            M[j + 3, j + 3] += d.transverse_kg_m2
            G[j + 2, j + 3] += d.polar_kg_m2
            G[j + 3, j + 2] -= d.polar_kg_m2
    K_shaft = K.copy()
    C += train.rayleigh_stiffness_s * K_shaft
    flexible = []
    for c, (a, b) in zip(train.couplings, coupling_nodes, strict=True):
        if c.kind != "flexible":
            continue
        for off, kk, cc in ((0, c.lateral_stiffness_n_m, c.lateral_damping_n_s_m),
                            (2, c.angular_stiffness_n_m_rad, c.angular_damping_n_m_s_rad)):
            for ax in (0, 1):
                ia, ib = 4 * a + off + ax, 4 * b + off + ax
                for mat_, v in ((K, kk), (C, cc)):
                    mat_[ia, ia] += v
                    mat_[ib, ib] += v
                    mat_[ia, ib] -= v
                    mat_[ib, ia] -= v
        flexible.append((a, b, c.lateral_stiffness_n_m, c.lateral_damping_n_s_m, c.kinematic_offset_m,
                         c.kinematic_phase_rad, c.kinematic_direction_rad))
    T = _slope_to_rotation(nd)

    def rot(A: np.ndarray) -> np.ndarray:
        return T.T @ A @ T

    M, K, Kc, Ks, K_shaft, Kcirc, G, C = (rot(A) for A in (M, K, Kc, Ks, K_shaft, Kcirc, G, C))
    C = C + train.rayleigh_mass_1_s * M
    asm_gravity = np.zeros(nd)
    ty = np.zeros(nd)
    ty[1::4] = 1.0
    asm_gravity = -train.gravity_m_s2 * (M @ ty)
    sup_nodes, centres, bearings = [], [], []
    ub_nodes, ub_amount, ub_angle = [], [], []
    for i, r in enumerate(train.rotors):
        for s in r.supports:
            sup_nodes.append(int(rotor_nodes[i][s.station]))
            centres.append((s.centre_x_m, s.centre_y_m))
            bearings.append(s.bearing)
        for u in r.unbalances:
            ub_nodes.append(int(rotor_nodes[i][u.station]))
            ub_amount.append(u.amount_kg_m)
            ub_angle.append(u.angle_rad)
    return Assembly(
        train=train, node_z_m=np.array(node_z), node_rotor=np.array(node_rotor), rotor_nodes=rotor_nodes,
        M=M, K=K, K_cos=Kc, K_sin=Ks, K_shaft=K_shaft, K_circ=Kcirc, G=G, C=C, gravity_n=asm_gravity,
        support_nodes=np.array(sup_nodes, dtype=int), support_centres_m=np.array(centres, dtype=float).reshape(-1, 2),
        bearings=bearings, unbalance_nodes=np.array(ub_nodes, dtype=int),
        unbalance_kg_m=np.array(ub_amount, dtype=float), unbalance_angle_rad=np.array(ub_angle, dtype=float),
        flexible=flexible, coupling_nodes=coupling_nodes,
    )
