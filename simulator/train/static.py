"""The static state of a train: Newton's method on the nonlinear bearings under gravity and offsets.

The mean (time-averaged) equations at spin speed Ω: (K + η Ω K_circ) q = f_gravity + Σ_b B_b f_b(q_b − c_b, 0, Ω),
with the asymmetric stiffness at its mean and the bearings' own forces (the oil film's static
load–eccentricity law, its attitude angle included). The Jacobian takes each bearing's static
stiffness by central differences of its force, so any bearing with ``force_n`` serves.
The load (gravity and the bearing offsets together) is raised in steps when a full step does not converge.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .fe import Assembly, assemble
from .model import Train, TrainError


@dataclass
class StaticState:
    """The train at rest on its oil films at speed ``speed_rad_s``.

    Attributes
    ----------
    q : ndarray (n_dof,)
        Node displacements [x, y, θx, θy] (m, rad) from the straight shaft-line axis.
    journal_m : ndarray (n_bearings, 2)
        Journal position relative to its bearing centre.
    bearing_load_n : ndarray (n_bearings, 2)
        Force of the journal on each bearing (gravity down gives a negative y).
    eccentricity : ndarray (n_bearings,)
        |journal − centre| / clearance (for a two-lobe or tilting-pad bearing its assembled clearance; the
        test for touching uses the bearing's own ``film_eccentricity``).
    attitude_angle_deg : ndarray (n_bearings,)
        Angle from the load on the film to the journal displacement, positive in the direction of
        rotation (the convention of ``SimulationResult.attitude_angle_deg``).
    coupling_load : list of ndarray (4,)
        Per coupling: shear (N, x and y) and moment (N·m, about x and y) that the rotor behind it
        (the one closer to station 0 of the train) receives from the coupling.
    """

    assembly: Assembly
    speed_rad_s: float
    q: np.ndarray
    journal_m: np.ndarray
    bearing_load_n: np.ndarray
    eccentricity: np.ndarray
    attitude_angle_deg: np.ndarray
    coupling_load: list
    iterations: int


def bearing_forces(asm: Assembly, q: np.ndarray, speed_rad_s: float,
                   qd: np.ndarray | None = None) -> np.ndarray:
    """Force of each bearing's film on its journal (n_bearings, 2), N."""
    out = np.zeros((len(asm.bearings), 2))
    for b, (node, brg) in enumerate(zip(asm.support_nodes, asm.bearings, strict=True)):
        x = q[4 * node] - asm.support_centres_m[b, 0]
        y = q[4 * node + 1] - asm.support_centres_m[b, 1]
        vx = 0.0 if qd is None else qd[4 * node]
        vy = 0.0 if qd is None else qd[4 * node + 1]
        out[b] = brg.force_n(float(x), float(y), float(vx), float(vy), float(speed_rad_s))
    return out


def _residual(asm: Assembly, Keff: np.ndarray, q: np.ndarray, speed: float, load: float,
              centres: np.ndarray) -> np.ndarray:
    r = Keff @ q - load * asm.gravity_n
    saved = asm.support_centres_m
    asm.support_centres_m = centres
    try:
        f = bearing_forces(asm, q, speed)
    finally:
        asm.support_centres_m = saved
    for b, node in enumerate(asm.support_nodes):
        r[4 * node: 4 * node + 2] -= f[b]
    return r


def _bearing_jacobian(brg, x: float, y: float, speed: float) -> np.ndarray:
    """∂f/∂(x, y) of one bearing by central differences (step 1e-6 of its clearance)."""
    h = 1e-6 * float(brg.clearance_m)
    J = np.empty((2, 2))
    for k in range(2):
        dx, dy = (h, 0.0) if k == 0 else (0.0, h)
        fp = np.array(brg.force_n(x + dx, y + dy, 0.0, 0.0, speed))
        fm = np.array(brg.force_n(x - dx, y - dy, 0.0, 0.0, speed))
        J[:, k] = (fp - fm) / (2 * h)
    return J


def film_eccentricity(brg, x_m: float, y_m: float) -> float:
    """How close the journal is to the wall of its film (1: touching): the bearing's own measure where it
    has one (a two-lobe or tilting-pad bore is not a circle of radius c), else |r|/c."""
    f = getattr(brg, "film_eccentricity", None)
    if f is not None:
        return float(f(float(x_m), float(y_m)))
    return math.hypot(x_m, y_m) / float(brg.clearance_m)


def _eccentricities(asm: Assembly, q: np.ndarray, centres: np.ndarray) -> np.ndarray:
    out = np.empty(len(asm.bearings))
    for b, node in enumerate(asm.support_nodes):
        d = q[4 * node: 4 * node + 2] - centres[b]
        out[b] = film_eccentricity(asm.bearings[b], d[0], d[1])
    return out


def static_state(train: Train | Assembly, speed_rpm: float, *, tol_n: float = 1e-6, max_iter: int = 60,
                 q0: np.ndarray | None = None) -> StaticState:
    """Newton solution of the train's static state at ``speed_rpm``.

    Raises
    ------
    TrainError
        When no state with every journal inside its clearance exists (an offset too large for the
        clearance, or a bearing that cannot carry its load at this speed); the message names the bearing.
    """
    asm = train if isinstance(train, Assembly) else assemble(train)
    if not (np.isfinite(speed_rpm) and speed_rpm > 0):
        raise TrainError(f"speed_rpm must be positive (got {speed_rpm!r}): an oil film carries no load at rest")
    speed = speed_rpm * math.pi / 30.0
    Keff = asm.mean_stiffness(speed, asm.train.internal_damping_s)
    centres_full = asm.support_centres_m.copy()
    q = np.zeros(asm.n_dof) if q0 is None else np.array(q0, dtype=float)
    scale = max(1.0, float(np.abs(asm.gravity_n).sum()))
    lam, step, total_iter = (1.0, 1.0, 0) if q0 is not None else (0.0, 1.0, 0)
    # the shaft's deflection that carries every journal with its bearing centre (stiff springs at the
    # centres): the predictor as the offsets are raised, so each journal stays near its moving centre
    kb = 1e3 * float(np.max(np.abs(np.diag(asm.K))))
    Ks = Keff.copy()
    f = np.zeros(asm.n_dof)
    for b, node in enumerate(asm.support_nodes):
        for ax in range(2):
            Ks[4 * node + ax, 4 * node + ax] += kb
            f[4 * node + ax] += kb * centres_full[b, ax]
    q_centres = np.linalg.solve(Ks, f)
    if q0 is None:
        q = np.zeros(asm.n_dof)  # zero weight and offsets: the straight line with centred journals
    q_try = q
    while True:
        target = min(1.0, lam + step)
        centres = centres_full * target  # gravity and bearing offsets are raised together
        guess = q + (target - lam) * q_centres if q0 is None else q
        q_try, ok, it = _newton(asm, Keff, guess, speed, target, centres, tol_n * scale, max_iter)
        total_iter += it
        if ok:
            q, lam = q_try, target
            if lam >= 1.0:
                break
            step = min(1.0 - lam, step * 2)
        else:
            step /= 4
            if step < 1e-3:
                ecc = _eccentricities(asm, q_try, centres)
                worst = int(np.nanargmax(ecc)) if np.any(np.isfinite(ecc)) else 0
                name = _support_name(asm, worst)
                raise TrainError(
                    f"no static state with every journal inside its clearance at {speed_rpm:g} r/min "
                    f"(bearing {name} reaches a film eccentricity {ecc[worst]:.2f} beyond {100 * lam:.0f} % of "
                    f"the weight and offsets): reduce the bearing offsets, enlarge that bearing or raise the speed")
    return _state(asm, q, speed, centres_full, total_iter)


def _support_name(asm: Assembly, b: int) -> str:
    i, s = asm.train.supports()[b]
    return s.name or f"{b} (rotor {asm.train.rotors[i].name!r}, station {s.station})"


def _newton(asm: Assembly, Keff: np.ndarray, q: np.ndarray, speed: float, load: float, centres: np.ndarray,
            tol: float, max_iter: int) -> tuple[np.ndarray, bool, int]:
    q = q.copy()
    r = _residual(asm, Keff, q, speed, load, centres)
    if not np.all(np.isfinite(r)):
        return q, False, 0
    for it in range(1, max_iter + 1):
        J = Keff.copy()
        for b, node in enumerate(asm.support_nodes):
            d = q[4 * node: 4 * node + 2] - centres[b]
            J[4 * node: 4 * node + 2, 4 * node: 4 * node + 2] -= _bearing_jacobian(asm.bearings[b], d[0], d[1], speed)
        try:
            dq = np.linalg.solve(J, -r)
        except np.linalg.LinAlgError:
            return q, False, it
        # keep every journal inside its clearance: shorten the step so no ε exceeds (1 + ε_old)/2
        alpha = 1.0
        for b, node in enumerate(asm.support_nodes):
            brg = asm.bearings[b]
            d0 = q[4 * node: 4 * node + 2] - centres[b]
            dd = dq[4 * node: 4 * node + 2]
            lim = 0.5 * (1.0 + film_eccentricity(brg, d0[0], d0[1]))
            while film_eccentricity(brg, *(d0 + alpha * dd)) > lim and alpha > 1e-6:
                alpha *= 0.5
        r_norm = float(np.linalg.norm(r))
        while True:
            q_new = q + alpha * dq
            r_new = _residual(asm, Keff, q_new, speed, load, centres)
            if np.all(np.isfinite(r_new)) and (np.linalg.norm(r_new) < r_norm or alpha < 1e-4):
                break
            if alpha < 1e-12:
                return q, False, it
            alpha *= 0.5
        q, r = q_new, r_new
        if not np.all(np.isfinite(r)):
            return q, False, it
        if np.linalg.norm(r) < tol and np.linalg.norm(alpha * dq) < 1e-9 * max(1e-3, np.abs(q).max()):
            return q, True, it
        if np.linalg.norm(r) < tol * 1e-3:
            return q, True, it
    return q, bool(np.linalg.norm(r) < tol), max_iter


def _state(asm: Assembly, q: np.ndarray, speed: float, centres: np.ndarray, iterations: int) -> StaticState:
    f = bearing_forces(asm, q, speed)
    journal = np.array([q[4 * n: 4 * n + 2] for n in asm.support_nodes]) - centres
    clear = np.array([float(b.clearance_m) for b in asm.bearings])
    ecc = np.hypot(journal[:, 0], journal[:, 1]) / clear
    load = -f
    a = np.arctan2(journal[:, 1], journal[:, 0]) - np.arctan2(load[:, 1], load[:, 0])
    att = np.degrees(np.angle(np.exp(1j * a)))
    film = _eccentricities(asm, q, centres)
    if np.any(film >= 1.0):
        b = int(np.argmax(film))
        raise TrainError(f"bearing {_support_name(asm, b)}: the journal sits outside its clearance at rest "
                         f"(film eccentricity {film[b]:.2f}); reduce the offsets or enlarge the clearance")
    return StaticState(assembly=asm, speed_rad_s=speed, q=q, journal_m=journal, bearing_load_n=load,
                       eccentricity=ecc, attitude_angle_deg=att, coupling_load=coupling_loads(asm, q, speed, f),
                       iterations=iterations)


def coupling_loads(asm: Assembly, q: np.ndarray, speed: float, f_bearing: np.ndarray) -> list[np.ndarray]:
    """Shear (x, y) and moment (about x, y) each coupling puts on the rotor behind it, static."""
    out = []
    train = asm.train
    for i, ((a, b), c) in enumerate(zip(asm.coupling_nodes, train.couplings, strict=True)):
        if c.kind == "flexible":
            ia, ib = slice(4 * a, 4 * a + 4), slice(4 * b, 4 * b + 4)
            k = np.array([c.lateral_stiffness_n_m] * 2 + [c.angular_stiffness_n_m_rad] * 2)
            out.append(k * (q[ib] - q[ia]))
            continue
        # rigid: the generalised force the left rotor's own elements, disks, gravity and bearings leave
        # unbalanced at the shared node is what the coupling supplies
        left = _single_rotor_assembly(asm, i)
        Kl = left.mean_stiffness(speed, train.internal_damping_s)
        nodes = asm.rotor_nodes[i]
        dofs = np.concatenate([np.arange(4 * n, 4 * n + 4) for n in nodes])
        ql = q[dofs]
        r = Kl @ ql - left.gravity_n
        for bi, (ri, s) in enumerate(train.supports()):
            if ri == i:
                j = 4 * s.station
                r[j: j + 2] -= f_bearing[bi]
        out.append(r[-4:].copy())
    return out


def _single_rotor_assembly(asm: Assembly, i: int) -> Assembly:
    cache = asm.__dict__.setdefault("_single", {})
    if i not in cache:
        r = asm.train.rotors[i]
        t = replace(asm.train, rotors=(r,), couplings=())
        cache[i] = assemble(t)
    return cache[i]


def aligned_offsets(train: Train, speed_rpm: float) -> np.ndarray:
    """Bearing-centre moves (n_bearings, 2), m, that make the train's couplings carry no shear and no moment.

    Each rotor is solved alone on its own bearings (the coupling cut); each following rotor's bearings are
    then moved as a rigid line so its flange meets the flange before it in position and slope (x and y):
    a rotor on two bearings is statically determinate, so the move displaces it rigidly and leaves its
    loads unchanged. This is the catenary (and its horizontal counterpart from the attitude angles).
    A rotor on a single bearing cannot stand alone: there the move zeroes the coupling moment only.
    """
    moves = np.zeros((len(train.supports()), 2))
    first = {}
    k = 0
    for i, r in enumerate(train.rotors):
        first[i] = k
        k += len(r.supports)
    z0 = train.rotor_start_z_m()
    prev_flange = None  # (x, y, θx, θy) of the last station of rotor i−1 after its move
    for i, r in enumerate(train.rotors):
        if len(r.supports) < 2:
            raise TrainError(f"rotor {r.name!r} has one bearing: the aligned reference of an overhung rotor is "
                             f"not defined by cutting the coupling; give its bearing position directly")
        alone = static_state(replace(train, rotors=(r,), couplings=()), speed_rpm)
        q = alone.q
        zs = z0[i] + r.station_z_m()
        shift_a = np.zeros(2)
        shift_b = np.zeros(2)  # line a + b (z − z_start)
        if prev_flange is not None:
            here = q[0:4]
            # slopes: ∂x/∂z = θy, ∂y/∂z = −θx
            slope_prev = np.array([prev_flange[3], -prev_flange[2]])
            slope_here = np.array([here[3], -here[2]])
            shift_a = prev_flange[0:2] - here[0:2]
            shift_b = slope_prev - slope_here
        for j, s in enumerate(r.supports):
            moves[first[i] + j] = shift_a + shift_b * (zs[s.station] - zs[0])
        end = q[-4:].copy()
        L = zs[-1] - zs[0]
        end[0:2] += shift_a + shift_b * L
        end[2] -= shift_b[1]
        end[3] += shift_b[0]
        prev_flange = end
    return moves


def with_moves(train: Train, moves: np.ndarray) -> Train:
    """The train with every bearing centre moved by ``moves`` (n_bearings, 2)."""
    rotors = []
    k = 0
    for r in train.rotors:
        sup = []
        for s in r.supports:
            sup.append(replace(s, centre_x_m=s.centre_x_m + float(moves[k, 0]),
                               centre_y_m=s.centre_y_m + float(moves[k, 1])))
            k += 1
        rotors.append(replace(r, supports=tuple(sup)))
    return replace(train, rotors=tuple(rotors))
