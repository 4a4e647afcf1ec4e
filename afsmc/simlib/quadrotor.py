"""Vectorised point-mass quadrotor: the shared dynamics of the UAV simulators.

Every array has the runs along its last axis; vectors are ``(3, runs)`` (x, y, z;
z up).  One call of :func:`fly` simulates one manoeuvre for all runs at once; the
only Python loop is over time steps.  See ``docs/simulation.md`` for the equations.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
_Array = npt.NDArray[Any]  # float32 in the flight loop

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
    flight = _Flight(runs, rng, start, goal, v_max=v_max, a_max=a_max,
                     payload_mass=payload_mass, settle=settle, dwell=dwell,
                     from_ground=from_ground, ground_goal=ground_goal, grip=grip,
                     vehicle=vehicle, env=env, gains=gains, dt=dt, t_max=t_max)
    steps = round(t_max / dt)
    for k in range(1, steps + 1):
        if not flight.step(k, rng):
            break
    return flight.result()


class _Flight:
    """The runs of one manoeuvre: the reference path, the controller's constants, each run's
    conditions and state, and the results of the runs already finished. The state arrays
    hold the still-active runs (``idx`` maps them to runs); the results are indexed by run."""

    def __init__(self, runs: int, rng: np.random.Generator, start: FloatArray,
                 goal: FloatArray, *, v_max: float, a_max: float, payload_mass: float,
                 settle: Settle, dwell: float, from_ground: bool, ground_goal: bool,
                 grip: Grip | None, vehicle: Vehicle, env: Environment, gains: Gains,
                 dt: float, t_max: float) -> None:
        self.n = runs
        self.v_max, self.a_max = v_max, a_max
        self.settle, self.from_ground, self.ground_goal = settle, from_ground, ground_goal
        self.grip, self.vehicle, self.gains, self.dt = grip, vehicle, gains, dt
        self._path(start, goal)
        self._constants(payload_mass)
        self._conditions(rng, env)
        self._initial_state(dwell, t_max)

    def _path(self, start: FloatArray, goal: FloatArray) -> None:
        """The straight reference from `start` to `goal`, one per run if either differs."""
        n = self.n
        start = np.asarray(start, dtype=float).reshape(3, -1)
        goal = np.asarray(goal, dtype=float).reshape(3, -1)
        self.per_run_path = start.shape[1] > 1 or goal.shape[1] > 1
        if self.per_run_path:
            start = np.broadcast_to(start, (3, n)).copy()
            goal = np.broadcast_to(goal, (3, n)).copy()
        delta = goal - start
        dist = np.sqrt(np.sum(delta**2, axis=0))
        self.start, self.goal = start, goal
        self.direction = delta / np.maximum(dist, 1e-12)
        self.prof = _Profile(dist, self.v_max, self.a_max)

    def _constants(self, payload_mass: float) -> None:
        """Mass, drag, gains and thrust limits."""
        vehicle, gains = self.vehicle, self.gains
        m = self.m = vehicle.mass + payload_mass
        self.kd_air = np.array([vehicle.drag_h, vehicle.drag_h, vehicle.drag_v])[:, None]
        self.ki = np.array(gains.ki)[:, None]
        # The flight loop runs in float32 (half the memory traffic; errors far below the noise).
        self.mkp = (m * np.array(gains.kp)[:, None]).astype(_F)
        self.mkd = (m * np.array(gains.kd)[:, None]).astype(_F)
        self.mki = (m * self.ki).astype(_F)
        self.kd_air32 = self.kd_air.astype(_F)
        self.f_max = vehicle.max_thrust
        self.tan2 = math.tan(vehicle.max_tilt) ** 2
        self.w0 = vehicle.mass * G
        self.g_vec = np.array([0.0, 0.0, G])[:, None]
        self.g_vec32 = self.g_vec.astype(_F)

    def _conditions(self, rng: np.random.Generator, env: Environment) -> None:
        """Per-run conditions: drive efficiency, steady horizontal wind; gusts and the
        estimator error start in their stationary law."""
        n = self.n
        self.eff = 1.0 + self.vehicle.efficiency_sd * rng.standard_normal(n)
        self.wind_mean = np.zeros((3, n))
        self.wind_mean[:2] = env.mean_wind_sd * rng.standard_normal((2, n))
        gust_sd = np.array(env.gust_sd)[:, None]
        pn_sd = np.array(env.pos_noise_sd)[:, None]
        self.vn_sd = np.array(env.vel_noise_sd)[:, None]
        self.gust = gust_sd * rng.standard_normal((3, n))
        self.perr = pn_sd * rng.standard_normal((3, n))
        self.verr = self.vn_sd * rng.standard_normal((3, n))
        self.phi_g = math.exp(-env.sensor_period / env.gust_tau)
        self.phi_p = math.exp(-env.sensor_period / env.pos_noise_tau)
        self.c_g = gust_sd * math.sqrt(1 - self.phi_g**2)
        self.c_p = pn_sd * math.sqrt(1 - self.phi_p**2)
        self.sensor_every = max(1, round(env.sensor_period / self.dt))

    def _initial_state(self, dwell: float, t_max: float) -> None:
        """Position, velocity, thrust and integrator at the start; counters and results."""
        n, kd_air, wind_mean = self.n, self.kd_air, self.wind_mean
        self.pos = np.broadcast_to(self.start, (3, n)).astype(_F)
        self.vel = np.zeros((3, n), dtype=_F)
        if self.from_ground:
            self.force = np.zeros((3, n), dtype=_F)
            self.integ = np.zeros((3, n), dtype=_F)
        else:
            # Airborne in trim: thrust balances weight and steady drag, held by the integrator.
            self.force = (-kd_air * wind_mean).astype(_F)
            self.force[2] += self.m * G
            self.integ = np.clip(-kd_air * wind_mean / (self.m * self.ki), -self.gains.i_limit,
                                 self.gains.i_limit).astype(_F)
        self.wind_mean = wind_mean.astype(_F)
        self.gust = self.gust.astype(_F)
        self.perr = self.perr.astype(_F)
        self.verr = self.verr.astype(_F)
        self.c_g, self.c_p, self.vn_sd = (self.c_g.astype(_F), self.c_p.astype(_F),
                                          self.vn_sd.astype(_F))
        # drag force of the wind on the hovering body
        self.drag_w = self.kd_air32 * (self.wind_mean + self.gust)
        self.goal32 = self.goal.astype(_F)

        self.alpha = 1.0 - math.exp(-self.dt / self.vehicle.tau_thrust)
        self.hold_steps = max(1, round(self.settle.hold / self.dt))
        self.need = (1 if self.ground_goal else self.hold_steps) + round(dwell / self.dt)
        self.counter = np.zeros(n, dtype=np.int64)  # consecutive settled steps, then dwell steps
        self.alive = np.ones(n, dtype=bool)  # rows of runs still flying
        self.energy = np.zeros(n)  # J, before the efficiency factor
        self.hazard = np.zeros(n)

        # Results are indexed by run; the state arrays shrink to the still-active runs.
        self.idx = np.arange(n)
        self.duration = np.full(n, t_max)
        self.energy_out = np.zeros(n)
        self.hazard_out = np.zeros(n)
        self.error_out = np.zeros((3, n))
        self.completed = np.zeros(n, dtype=bool)

    def step(self, k: int, rng: np.random.Generator) -> bool:
        """Advance every active run to time k * dt; False once no run is active."""
        t = k * self.dt
        if k % self.sensor_every == 0:
            self._sense(rng)
        est_p, est_v = self._control(t)
        acc = self._move()
        if self.grip is not None:
            self._grip_hazard(self.grip, acc)
        ok = self._settled(t, est_p, est_v)
        if ok is None:
            return True
        return self._finish(t, ok)

    def _sense(self, rng: np.random.Generator) -> None:
        """A sensor update: new gusts and estimator errors."""
        noise = rng.standard_normal((9, self.idx.size), dtype=_F)
        self.gust *= self.phi_g
        self.gust += self.c_g * noise[0:3]
        self.perr *= self.phi_p
        self.perr += self.c_p * noise[3:6]
        self.verr = self.vn_sd * noise[6:9]
        self.drag_w = self.kd_air32 * (self.wind_mean + self.gust)

    def _control(self, t: float) -> tuple[_Array, _Array]:
        """Track the reference at time t: the thrust lags towards the PID's limited command.
        Returns the estimated position and velocity."""
        m, direction, dt = self.m, self.direction, self.dt
        s, sd, sdd = self.prof.at(t)
        ref_p = (self.start + direction * s).astype(_F)
        ref_v = (direction * sd).astype(_F)
        # Feed-forward: reference acceleration, gravity and the drag of the reference speed.
        f_ff = (m * (direction * sdd + self.g_vec) + self.kd_air * (direction * sd)).astype(_F)

        # PID on the estimated state -> acceleration command -> limited thrust vector.
        est_p = self.pos + self.perr
        est_v = self.vel + self.verr
        e = ref_p - est_p
        if self.from_ground:
            e_i = e * (self.pos[2] > 0.02)  # no integration while still on the ground
            self.integ += e_i * dt
        else:
            self.integ += e * dt
        np.clip(self.integ, -self.gains.i_limit, self.gains.i_limit, out=self.integ)
        f_cmd = self.mkp * e + self.mkd * (ref_v - est_v) + self.mki * self.integ + f_ff
        f_max = self.f_max
        fz = np.clip(f_cmd[2], 0.0, f_max)
        fz2 = fz * fz
        fh2 = f_cmd[0] ** 2 + f_cmd[1] ** 2
        lim2 = np.minimum(self.tan2 * fz2, f_max**2 - fz2)
        scale = np.sqrt(np.minimum(1.0, lim2 / np.maximum(fh2, 1e-12)))
        f_cmd[0] *= scale
        f_cmd[1] *= scale
        f_cmd[2] = fz
        self.force += self.alpha * (f_cmd - self.force)
        return est_p, est_v

    def _move(self) -> _Array:
        """Integrate velocity and position one step, and the energy drawn; returns the
        acceleration."""
        dt, vehicle = self.dt, self.vehicle
        force, vel, pos = self.force, self.vel, self.pos
        acc = (force - self.kd_air32 * vel + self.drag_w) * (1.0 / self.m) - self.g_vec32
        vel += acc * dt
        pos += vel * dt
        if self.from_ground or self.ground_goal:
            down = pos[2] <= 0.0
            if down.any():
                # Ground contact: no sinking, no sliding.
                pos[2, down] = 0.0
                vel[:, down] = 0.0
                acc[:, down] = -self.g_vec

        ratio = np.sqrt(np.sum(force * force, axis=0)) / self.w0
        self.energy += (vehicle.p_avionics + vehicle.p_hover * ratio * np.sqrt(ratio)) * dt
        return acc

    def _grip_hazard(self, grip: Grip, acc: _Array) -> None:
        """Gripper load: the payload's share of the inertial force plus its own drag."""
        air = self.vel - self.wind_mean - self.gust
        airspeed = np.sqrt(np.sum(air * air, axis=0))
        load = grip.payload_mass * (acc + self.g_vec32) - grip.drag * air * airspeed
        lratio = np.sqrt(np.sum(load * load, axis=0)) / (grip.payload_mass * G)
        self.hazard += grip.lam0 * np.exp(grip.beta * (lratio - 1.0)) * self.dt

    def _settled(self, t: float, est_p: _Array,
                 est_v: _Array) -> npt.NDArray[np.bool_] | None:
        """Which runs are at the goal at time t; None before any can be."""
        if self.ground_goal:
            ok: npt.NDArray[np.bool_] = self.pos[2] <= 0.0
        elif t + 1e-9 >= self.prof.t_last or self.per_run_path:
            settle = self.settle
            d = est_p - self.goal32
            ok = np.sum(d * d, axis=0) < settle.pos_tol**2
            ok &= np.sum(est_v * est_v, axis=0) < settle.vel_tol**2
            if self.per_run_path:
                ok &= t + 1e-9 >= self.prof.t_end
        else:
            return None
        return ok

    def _finish(self, t: float, ok: npt.NDArray[np.bool_]) -> bool:
        """Count settled steps and record the runs that are done at time t; False once no
        run is active."""
        # Before settling the count restarts on leaving tolerance; the dwell always counts on.
        self.counter = np.where(ok | (self.counter >= self.hold_steps), self.counter + 1, 0)
        done = self.alive & (self.counter >= self.need)
        if not done.any():
            return True
        runs_done = self.idx[done]
        self.duration[runs_done] = t
        self.energy_out[runs_done] = self.energy[done]
        self.hazard_out[runs_done] = self.hazard[done]
        self.error_out[:, runs_done] = self._error(done)
        self.completed[runs_done] = True
        self.alive &= ~done
        n_alive = int(self.alive.sum())
        if n_alive == 0:
            return False
        if n_alive * 2 < self.idx.size:  # compact once half the rows are finished runs
            self._compact(self.alive)
        return True

    def _error(self, sel: npt.NDArray[np.bool_]) -> FloatArray:
        """True position minus goal of the rows `sel`."""
        if self.per_run_path:
            return (self.pos - self.goal)[:, sel]
        return self.pos[:, sel] - self.goal

    def _compact(self, keep: npt.NDArray[np.bool_]) -> None:
        """Drop the rows of finished runs from the state arrays."""
        self.idx = self.idx[keep]
        self.pos, self.vel = self.pos[:, keep], self.vel[:, keep]
        self.force, self.integ = self.force[:, keep], self.integ[:, keep]
        self.gust, self.perr, self.verr = self.gust[:, keep], self.perr[:, keep], self.verr[:, keep]
        self.wind_mean, self.drag_w = self.wind_mean[:, keep], self.drag_w[:, keep]
        self.counter, self.energy = self.counter[keep], self.energy[keep]
        self.hazard = self.hazard[keep]
        self.alive = self.alive[keep]
        if self.per_run_path:
            self.start, self.goal = self.start[:, keep], self.goal[:, keep]
            self.direction = self.direction[:, keep]
            self.goal32 = self.goal32[:, keep]
            self.prof = _Profile(self.prof.dist[keep], self.v_max, self.a_max)

    def result(self) -> FlightResult:
        """The results; runs still flying get their energy, hazard and error so far."""
        if not self.alive.all() or self.idx.size < self.n or not self.completed.all():
            sel = self.alive
            left = self.idx[sel]
            self.energy_out[left] = self.energy[sel]
            self.hazard_out[left] = self.hazard[sel]
            self.error_out[:, left] = self._error(sel)
        return FlightResult(
            duration=self.duration,
            battery=self.energy_out / (self.eff * self.vehicle.joules_per_unit),
            final_error=self.error_out,
            completed=self.completed,
            hazard=self.hazard_out,
        )
