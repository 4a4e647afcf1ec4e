"""Vectorised point-mass quadrotor: the shared dynamics of the UAV simulators.

Every array has the runs along its last axis; vectors are ``(3, runs)`` (x, y, z;
z up).  One call of :func:`fly` simulates one manoeuvre for all runs at once; the
only Python loop is over time steps.  See ``docs/simulation.md`` for the equations.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

G = 9.81  # m/s^2
_F = np.float32
AIR_DENSITY = 1.225  # kg/m^3


@dataclass(frozen=True)
class Vehicle:
    """A small quadrotor (~1.5 kg, 10-inch props, 4S 2200 mAh pack)."""

    mass: float = 1.5  # kg, without payload
    thrust_to_weight: float = 2.0  # max total thrust / (mass * g)
    max_tilt: float = math.radians(35.0)  # thrust-vector tilt limit
    drag_h: float = 0.30  # N per m/s of airspeed, horizontal (linear drag)
    drag_v: float = 0.40  # N per m/s of airspeed, vertical
    tau_thrust: float = 0.12  # s, attitude + motor lag of the thrust vector
    # Power: P = P_avionics + P_hover * (|F| / (mass g))^1.5 (momentum theory).
    p_avionics: float = 15.0  # W, flight controller, companion computer, camera
    p_hover: float = 180.0  # W, electrical rotor power at hover without payload
    # Battery: 4S 2200 mAh = 32.6 Wh, 90 % usable -> 100 units.
    usable_energy_j: float = 0.9 * 14.8 * 2.2 * 3600.0
    efficiency_sd: float = 0.01  # per-run spread of drive efficiency (cell resistance, temperature)

    @property
    def joules_per_unit(self) -> float:
        return self.usable_energy_j / 100.0

    @property
    def max_thrust(self) -> float:
        return self.thrust_to_weight * self.mass * G

    @property
    def hover_endurance_s(self) -> float:
        return self.usable_energy_j / (self.p_avionics + self.p_hover)


@dataclass(frozen=True)
class Environment:
    """Wind and sensing conditions.  Per run: a steady wind; per step: gusts, sensor noise."""

    mean_wind_sd: float = 1.0  # m/s, per horizontal axis (speed is Rayleigh, mean ~1.25 m/s)
    gust_sd: tuple[float, float, float] = (0.6, 0.6, 0.25)  # m/s per axis (x, y, z)
    gust_tau: float = 2.0  # s, correlation time of the first-order (Dryden-like) gust
    pos_noise_sd: tuple[float, float, float] = (0.05, 0.05, 0.04)  # m, estimator position error
    pos_noise_tau: float = 1.0  # s, correlation time of the position error (GNSS/vision drift)
    vel_noise_sd: tuple[float, float, float] = (
        0.02,
        0.02,
        0.02,
    )  # m/s, white per update (IMU-fused)
    sensor_period: float = 0.2  # s, position fix / gust update rate (5 Hz)


@dataclass(frozen=True)
class Gains:
    """Cascaded-free PID on position, per axis (x, y, z), producing an acceleration command."""

    kp: tuple[float, float, float] = (2.25, 2.25, 4.0)  # 1/s^2: omega_n 1.5 and 2 rad/s
    kd: tuple[float, float, float] = (2.7, 2.7, 3.6)  # 1/s: zeta 0.9
    ki: tuple[float, float, float] = (0.3, 0.3, 0.6)  # 1/s^3
    i_limit: float = 5.0  # m*s, anti-windup clamp of the integral state


@dataclass(frozen=True)
class Settle:
    """When a manoeuvre counts as complete: the estimate is near the goal for `hold` s."""

    pos_tol: float = 0.25  # m
    vel_tol: float = 0.2  # m/s
    hold: float = 0.5  # s


@dataclass(frozen=True)
class Grip:
    """Slip hazard of a friction gripper: rate lam0 * exp(beta * (load/weight - 1))."""

    payload_mass: float
    lam0: float  # 1/s, slip rate at the static hover load
    beta: float  # sensitivity to load beyond 1 g
    drag: float = 0.05  # N per (m/s)^2, quadratic drag of the payload


@dataclass
class FlightResult:
    duration: FloatArray  # s
    battery: FloatArray  # charge units used
    final_error: FloatArray  # (3, runs) true position minus goal, m, at the end of the dwell
    completed: BoolArray  # False if a run hit the time limit
    hazard: FloatArray = field(default_factory=lambda: np.zeros(0))  # integrated slip hazard


class _Profile:
    """Trapezoidal (or triangular) rest-to-rest profile over `dist` (scalar or per run)."""

    def __init__(self, dist: FloatArray, v_max: float, a_max: float) -> None:
        self.a = a_max
        self.dist = dist
        self.t_a = np.minimum(v_max / a_max, np.sqrt(dist / a_max))
        self.v_p = a_max * self.t_a
        self.d_a = 0.5 * a_max * self.t_a**2
        t_c = (dist - 2 * self.d_a) / np.maximum(self.v_p, 1e-12)
        self.t1 = self.t_a + t_c
        self.t_end = self.t1 + self.t_a
        self.t_last = float(np.max(self.t_end))

    def at(self, t: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Arc length, speed and acceleration of the reference at time `t`."""
        a = self.a
        tc = np.minimum(t, self.t_end)
        acc_phase = tc < self.t_a
        dec_phase = tc > self.t1
        td = self.t_end - tc
        s = np.where(
            acc_phase,
            0.5 * a * tc**2,
            np.where(dec_phase, self.dist - 0.5 * a * td**2, self.d_a + self.v_p * (tc - self.t_a)),
        )
        sd = np.where(acc_phase, a * tc, np.where(dec_phase, a * td, self.v_p))
        sdd = np.where(acc_phase, a, np.where(dec_phase, -a, 0.0))
        sdd = np.where(t < self.t_end, sdd, 0.0)
        return s, sd, sdd


def profile_time(dist: float, v_max: float, a_max: float) -> float:
    """Duration of the reference profile over `dist` metres."""
    return float(_Profile(np.array([dist]), v_max, a_max).t_end[0])


def fly(
    runs: int,
    rng: np.random.Generator,
    start: FloatArray,
    goal: FloatArray,
    *,
    v_max: float,
    a_max: float,
    payload_mass: float = 0.0,
    settle: Settle = Settle(),
    dwell: float = 0.0,
    from_ground: bool = False,
    ground_goal: bool = False,
    grip: Grip | None = None,
    vehicle: Vehicle = Vehicle(),
    env: Environment = Environment(),
    gains: Gains = Gains(),
    dt: float = 0.1,
    t_max: float = 120.0,
) -> FlightResult:
    """Fly from `start` to `goal` (each ``(3,)`` or ``(3, runs)``) along a straight
    trapezoidal reference, then hover `dwell` seconds after settling.

    `from_ground`: start landed with motors off.  `ground_goal`: the goal is below
    ground; the manoeuvre ends at touchdown instead of settling.
    """
    n = runs
    start = np.asarray(start, dtype=float).reshape(3, -1)
    goal = np.asarray(goal, dtype=float).reshape(3, -1)
    per_run_path = start.shape[1] > 1 or goal.shape[1] > 1
    if per_run_path:
        start = np.broadcast_to(start, (3, n)).copy()
        goal = np.broadcast_to(goal, (3, n)).copy()
    delta = goal - start
    dist = np.sqrt(np.sum(delta**2, axis=0))
    direction = delta / np.maximum(dist, 1e-12)
    prof = _Profile(dist, v_max, a_max)

    m = vehicle.mass + payload_mass
    kd_air = np.array([vehicle.drag_h, vehicle.drag_h, vehicle.drag_v])[:, None]
    ki = np.array(gains.ki)[:, None]
    # The flight loop runs in float32 (half the memory traffic; errors far below the noise).
    mkp = (m * np.array(gains.kp)[:, None]).astype(_F)
    mkd = (m * np.array(gains.kd)[:, None]).astype(_F)
    mki = (m * ki).astype(_F)
    kd_air32 = kd_air.astype(_F)
    f_max = vehicle.max_thrust
    tan2 = math.tan(vehicle.max_tilt) ** 2
    w0 = vehicle.mass * G
    g_vec = np.array([0.0, 0.0, G])[:, None]
    g_vec32 = g_vec.astype(_F)

    # Per-run conditions: drive efficiency, steady horizontal wind; gusts and the
    # estimator error start in their stationary law.
    eff = 1.0 + vehicle.efficiency_sd * rng.standard_normal(n)
    wind_mean = np.zeros((3, n))
    wind_mean[:2] = env.mean_wind_sd * rng.standard_normal((2, n))
    gust_sd = np.array(env.gust_sd)[:, None]
    pn_sd = np.array(env.pos_noise_sd)[:, None]
    vn_sd = np.array(env.vel_noise_sd)[:, None]
    gust = gust_sd * rng.standard_normal((3, n))
    perr = pn_sd * rng.standard_normal((3, n))
    verr = vn_sd * rng.standard_normal((3, n))
    phi_g = math.exp(-env.sensor_period / env.gust_tau)
    phi_p = math.exp(-env.sensor_period / env.pos_noise_tau)
    c_g = gust_sd * math.sqrt(1 - phi_g**2)
    c_p = pn_sd * math.sqrt(1 - phi_p**2)
    sensor_every = max(1, round(env.sensor_period / dt))

    pos = np.broadcast_to(start, (3, n)).astype(_F)
    vel = np.zeros((3, n), dtype=_F)
    if from_ground:
        force = np.zeros((3, n), dtype=_F)
        integ = np.zeros((3, n), dtype=_F)
    else:
        # Airborne in trim: thrust balances weight and steady drag, held by the integrator.
        force = (-kd_air * wind_mean).astype(_F)
        force[2] += m * G
        integ = np.clip(-kd_air * wind_mean / (m * ki), -gains.i_limit, gains.i_limit).astype(_F)
    wind_mean = wind_mean.astype(_F)
    gust = gust.astype(_F)
    perr = perr.astype(_F)
    verr = verr.astype(_F)
    c_g, c_p, vn_sd = c_g.astype(_F), c_p.astype(_F), vn_sd.astype(_F)
    drag_w = kd_air32 * (wind_mean + gust)  # drag force of the wind on the hovering body
    goal32 = goal.astype(_F)

    alpha = 1.0 - math.exp(-dt / vehicle.tau_thrust)
    hold_steps = max(1, round(settle.hold / dt))
    need = (1 if ground_goal else hold_steps) + round(dwell / dt)
    counter = np.zeros(n, dtype=np.int64)  # consecutive settled steps, then dwell steps
    alive = np.ones(n, dtype=bool)  # rows of runs still flying
    energy = np.zeros(n)  # J, before the efficiency factor
    hazard = np.zeros(n)

    # Results are indexed by run; the state arrays shrink to the still-active runs.
    idx = np.arange(n)
    duration = np.full(n, t_max)
    energy_out = np.zeros(n)
    hazard_out = np.zeros(n)
    error_out = np.zeros((3, n))
    completed = np.zeros(n, dtype=bool)

    steps = round(t_max / dt)
    for k in range(1, steps + 1):
        t = k * dt
        if k % sensor_every == 0:
            noise = rng.standard_normal((9, idx.size), dtype=_F)
            gust *= phi_g
            gust += c_g * noise[0:3]
            perr *= phi_p
            perr += c_p * noise[3:6]
            verr = vn_sd * noise[6:9]
            drag_w = kd_air32 * (wind_mean + gust)
        s, sd, sdd = prof.at(t)
        ref_p = (start + direction * s).astype(_F)
        ref_v = (direction * sd).astype(_F)
        # Feed-forward: reference acceleration, gravity and the drag of the reference speed.
        f_ff = (m * (direction * sdd + g_vec) + kd_air * (direction * sd)).astype(_F)

        # PID on the estimated state -> acceleration command -> limited thrust vector.
        est_p = pos + perr
        est_v = vel + verr
        e = ref_p - est_p
        if from_ground:
            e_i = e * (pos[2] > 0.02)  # no integration while still on the ground
            integ += e_i * dt
        else:
            integ += e * dt
        np.clip(integ, -gains.i_limit, gains.i_limit, out=integ)
        f_cmd = mkp * e + mkd * (ref_v - est_v) + mki * integ + f_ff
        fz = np.clip(f_cmd[2], 0.0, f_max)
        fz2 = fz * fz
        fh2 = f_cmd[0] ** 2 + f_cmd[1] ** 2
        lim2 = np.minimum(tan2 * fz2, f_max**2 - fz2)
        scale = np.sqrt(np.minimum(1.0, lim2 / np.maximum(fh2, 1e-12)))
        f_cmd[0] *= scale
        f_cmd[1] *= scale
        f_cmd[2] = fz
        force += alpha * (f_cmd - force)

        acc = (force - kd_air32 * vel + drag_w) * (1.0 / m) - g_vec32
        vel += acc * dt
        pos += vel * dt
        if from_ground or ground_goal:
            down = pos[2] <= 0.0
            if down.any():
                # Ground contact: no sinking, no sliding.
                pos[2, down] = 0.0
                vel[:, down] = 0.0
                acc[:, down] = -g_vec

        ratio = np.sqrt(np.sum(force * force, axis=0)) / w0
        energy += (vehicle.p_avionics + vehicle.p_hover * ratio * np.sqrt(ratio)) * dt

        if grip is not None:
            # Gripper load: the payload's share of the inertial force plus its own drag.
            air = vel - wind_mean - gust
            airspeed = np.sqrt(np.sum(air * air, axis=0))
            load = grip.payload_mass * (acc + g_vec32) - grip.drag * air * airspeed
            lratio = np.sqrt(np.sum(load * load, axis=0)) / (grip.payload_mass * G)
            hazard += grip.lam0 * np.exp(grip.beta * (lratio - 1.0)) * dt

        if ground_goal:
            ok = pos[2] <= 0.0
        elif t + 1e-9 >= prof.t_last or per_run_path:
            d = est_p - goal32
            ok = np.sum(d * d, axis=0) < settle.pos_tol**2
            ok &= np.sum(est_v * est_v, axis=0) < settle.vel_tol**2
            if per_run_path:
                ok &= t + 1e-9 >= prof.t_end
        else:
            continue
        # Before settling the count restarts on leaving tolerance; the dwell always counts on.
        counter = np.where(ok | (counter >= hold_steps), counter + 1, 0)
        done = alive & (counter >= need)
        if not done.any():
            continue
        runs_done = idx[done]
        duration[runs_done] = t
        energy_out[runs_done] = energy[done]
        hazard_out[runs_done] = hazard[done]
        error_out[:, runs_done] = (pos - goal)[:, done] if per_run_path else pos[:, done] - goal
        completed[runs_done] = True
        alive &= ~done
        n_alive = int(alive.sum())
        if n_alive == 0:
            break
        if n_alive * 2 < idx.size:  # compact once half the rows are finished runs
            keep = alive
            idx = idx[keep]
            pos, vel, force, integ = pos[:, keep], vel[:, keep], force[:, keep], integ[:, keep]
            gust, perr, verr = gust[:, keep], perr[:, keep], verr[:, keep]
            wind_mean, drag_w = wind_mean[:, keep], drag_w[:, keep]
            counter, energy, hazard = counter[keep], energy[keep], hazard[keep]
            alive = alive[keep]
            if per_run_path:
                start, goal, direction = start[:, keep], goal[:, keep], direction[:, keep]
                goal32 = goal32[:, keep]
                prof = _Profile(prof.dist[keep], v_max, a_max)
    if not alive.all() or idx.size < n or not completed.all():
        sel = alive
        left = idx[sel]
        energy_out[left] = energy[sel]
        hazard_out[left] = hazard[sel]
        error_out[:, left] = (pos - goal)[:, sel] if per_run_path else pos[:, sel] - goal
    return FlightResult(
        duration=duration,
        battery=energy_out / (eff * vehicle.joules_per_unit),
        final_error=error_out,
        completed=completed,
        hazard=hazard_out,
    )
