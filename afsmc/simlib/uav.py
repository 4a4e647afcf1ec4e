"""Small-scale simulators of the UAV search-and-retrieve actions (Hoffmann et al.).

One simulator per abstract action of the paper's Fig. 1.  Durations in seconds,
battery in charge units (full = 100), failures as bool samples.  The arena is a grid
of CELL x CELL m squares searched at SEARCH_HEIGHT; see docs/simulation.md.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import numpy.typing as npt

from afsmc.simlib.quadrotor import (
    FlightResult,
    FloatArray,
    Grip,
    Settle,
    Vehicle,
    fly,
)
from afsmc.simlib.registry import Simulator

Outputs = Mapping[str, npt.NDArray[Any]]

VEHICLE = Vehicle()

CELL = 6.0  # m, side of an arena square (camera footprint at SEARCH_HEIGHT covers it)
SEARCH_HEIGHT = 10.0  # m, search, transport and return altitude
GRAB_HEIGHT = 0.6  # m, body height at which the gripper reaches the object
DEPOSIT_HEIGHT = 1.5  # m, release height over the deposit bin
LAND_FLARE_HEIGHT = 1.0  # m, where the final slow descent starts
PAYLOAD = 0.25  # kg, an object

SPOOL_UP = 1.5  # s, motor arming and spool-up before lift-off
SPOOL_DOWN = 1.0  # s, motor stop after touchdown
CHECK_WINDOW = 8.0  # s, hover self-test of IMU, GNSS, camera, gripper, ESCs
GNSS_WAIT_MEAN = 1.0  # s, extra wait for the position solution to converge (gamma)
CAMERA_DWELL = 1.0  # s, hover while the downward camera frame is captured and classified
GRIPPER_CLOSE = 1.5  # s, gripper closing time (the UAV holds position meanwhile)
GRIPPER_OPEN = 1.0  # s, release and confirm drop

# Self-test: probability that a subsystem is faulty, and the test statistic's
# fault offset and alarm threshold (in noise standard deviations).
SUBSYSTEM_FAULT = {"imu": 0.004, "gnss": 0.008, "camera": 0.006, "gripper": 0.004, "esc": 0.003}
FAULT_OFFSET = 6.0
ALARM_THRESHOLD = 4.0

# Grab succeeds with probability 1 / (1 + exp((e - CAPTURE_RADIUS) / CAPTURE_SOFTNESS)),
# e = horizontal distance between gripper and object when the gripper closes.
CAPTURE_RADIUS = 0.17  # m
CAPTURE_SOFTNESS = 0.02  # m
OBJECT_ESTIMATE_SD = 0.03  # m per axis, vision estimate of the object's position

# Transport drop: slip hazard rate GRIP_LAM0 * exp(GRIP_BETA * (load / weight - 1)).
GRIP = Grip(payload_mass=PAYLOAD, lam0=0.002, beta=8.0, drag=0.05)

# Recharge station (CC-CV): constant charge rate until the CV knee, then an
# exponential taper; terminated at a tenth of the CC current and reported full.
LOW_BATTERY = 30.0  # units, the low-battery threshold B_low recharge starts from
CHARGE_RATE = 0.5  # units/s in the CC phase (~530 W; high-rate cells on a fast charger)
CHARGE_RATE_SD = 0.0015  # relative, per run (cell temperature)
CV_KNEE = 85.0  # units, state of charge where the CV phase starts
CV_KNEE_SD = 0.1  # units, per run (internal resistance)
CUTOFF = 0.1  # terminate at this fraction of the CC current
DOCK_TIME = 5.0  # s, connector handshake before current flows
DOCK_TIME_SD = 0.1  # s

_HOVER = np.array([0.0, 0.0, SEARCH_HEIGHT])
_NEXT_CELL = np.array([CELL, 0.0, SEARCH_HEIGHT])


def _out(
    res: FlightResult, extra_time: FloatArray | float = 0.0, extra_battery: FloatArray | float = 0.0
) -> dict[str, npt.NDArray[Any]]:
    return {"duration": res.duration + extra_time, "battery": res.battery + extra_battery}


def _hover_units(seconds: FloatArray | float, payload: float = 0.0) -> FloatArray | float:
    """Battery units for hovering `seconds` (used for fixed waits outside the flight loop)."""
    w = ((VEHICLE.mass + payload) / VEHICLE.mass) ** 1.5
    watts = VEHICLE.p_avionics + VEHICLE.p_hover * w
    units: FloatArray | float = watts * np.asarray(seconds, dtype=float) / VEHICLE.joules_per_unit
    return units


def takeoff(runs: int, rng: np.random.Generator) -> Outputs:
    res = fly(runs, rng, np.zeros(3), _HOVER, v_max=1.5, a_max=1.0, from_ground=True)
    # Spool-up: avionics plus idling rotors (~5 % of hover power).
    spool = SPOOL_UP * (VEHICLE.p_avionics + 0.05 * VEHICLE.p_hover) / VEHICLE.joules_per_unit
    return _out(res, SPOOL_UP, spool)


def initialise(runs: int, rng: np.random.Generator) -> Outputs:
    res = fly(runs, rng, _HOVER, _HOVER, v_max=1.0, a_max=1.0, dwell=CHECK_WINDOW)
    wait = rng.gamma(9.0, GNSS_WAIT_MEAN / 9.0, runs)
    alarm = np.zeros(runs, dtype=bool)
    for p in SUBSYSTEM_FAULT.values():
        faulty = rng.random(runs) < p
        stat = FAULT_OFFSET * faulty + rng.standard_normal(runs)
        alarm |= stat > ALARM_THRESHOLD
    out = _out(res, wait, _hover_units(wait))
    out["fail"] = alarm
    return out


def search(runs: int, rng: np.random.Generator) -> Outputs:
    res = fly(runs, rng, _HOVER, _NEXT_CELL, v_max=3.0, a_max=1.5, dwell=CAMERA_DWELL)
    return _out(res)


def approach(runs: int, rng: np.random.Generator) -> Outputs:
    # The detected object lies anywhere in the current square.
    goal = np.empty((3, runs))
    goal[:2] = rng.uniform(-CELL / 2, CELL / 2, (2, runs))
    goal[2] = SEARCH_HEIGHT
    res = fly(runs, rng, _HOVER, goal, v_max=3.0, a_max=2.0)
    return _out(res)


def descend_grab(runs: int, rng: np.random.Generator) -> Outputs:
    goal = np.array([0.0, 0.0, GRAB_HEIGHT])
    res = fly(runs, rng, _HOVER, goal, v_max=1.0, a_max=0.5)
    return _out(res)


def grab(runs: int, rng: np.random.Generator) -> Outputs:
    at = np.array([0.0, 0.0, GRAB_HEIGHT])
    res = fly(
        runs,
        rng,
        at,
        at,
        v_max=1.0,
        a_max=1.0,
        settle=Settle(pos_tol=0.15, vel_tol=0.15),
        dwell=GRIPPER_CLOSE,
    )
    obj_err = OBJECT_ESTIMATE_SD * rng.standard_normal((2, runs))
    e = np.hypot(res.final_error[0] - obj_err[0], res.final_error[1] - obj_err[1])
    p_capture = 1.0 / (1.0 + np.exp((e - CAPTURE_RADIUS) / CAPTURE_SOFTNESS))
    out = _out(res)
    out["fail"] = rng.random(runs) >= p_capture
    return out


def ascend(runs: int, rng: np.random.Generator) -> Outputs:
    start = np.array([0.0, 0.0, GRAB_HEIGHT])
    res = fly(runs, rng, start, _HOVER, v_max=1.5, a_max=1.0, payload_mass=PAYLOAD)
    return _out(res)


def transport(runs: int, rng: np.random.Generator) -> Outputs:
    res = fly(
        runs,
        rng,
        _HOVER,
        _NEXT_CELL,
        v_max=2.5,
        a_max=1.2,
        payload_mass=PAYLOAD,
        grip=GRIP,
        settle=Settle(pos_tol=0.3, vel_tol=0.3),
    )
    out = _out(res)
    out["drop"] = rng.random(runs) < -np.expm1(-res.hazard)
    return out


def descend_deposit(runs: int, rng: np.random.Generator) -> Outputs:
    goal = np.array([0.0, 0.0, DEPOSIT_HEIGHT])
    res = fly(
        runs,
        rng,
        _HOVER,
        goal,
        v_max=1.0,
        a_max=0.5,
        payload_mass=PAYLOAD,
        settle=Settle(pos_tol=0.2, vel_tol=0.15),
    )
    return _out(res)


def deposit(runs: int, rng: np.random.Generator) -> Outputs:
    at = np.array([0.0, 0.0, DEPOSIT_HEIGHT])
    res = fly(
        runs,
        rng,
        at,
        at,
        v_max=1.0,
        a_max=1.0,
        payload_mass=PAYLOAD,
        settle=Settle(pos_tol=0.2, vel_tol=0.15),
        dwell=GRIPPER_OPEN,
    )
    return _out(res)


def ascend_empty(runs: int, rng: np.random.Generator) -> Outputs:
    start = np.array([0.0, 0.0, DEPOSIT_HEIGHT])
    res = fly(runs, rng, start, _HOVER, v_max=1.5, a_max=1.0)
    return _out(res)


def return_move(runs: int, rng: np.random.Generator) -> Outputs:
    res = fly(
        runs, rng, _HOVER, _NEXT_CELL, v_max=4.0, a_max=2.0, settle=Settle(pos_tol=0.3, vel_tol=0.3)
    )
    return _out(res)


def land(runs: int, rng: np.random.Generator) -> Outputs:
    flare = np.array([0.0, 0.0, LAND_FLARE_HEIGHT])
    down = fly(
        runs, rng, _HOVER, flare, v_max=1.5, a_max=0.8, settle=Settle(pos_tol=0.3, vel_tol=0.2)
    )
    # Final descent aims below ground so touchdown happens at the commanded sink rate.
    touch = fly(
        runs, rng, flare, np.array([0.0, 0.0, -0.5]), v_max=0.5, a_max=0.5, ground_goal=True
    )
    stop = SPOOL_DOWN * VEHICLE.p_avionics / VEHICLE.joules_per_unit
    return {
        "duration": down.duration + touch.duration + SPOOL_DOWN,
        "battery": down.battery + touch.battery + stop,
    }


def recharge_time(level: FloatArray | float, runs: int, rng: np.random.Generator) -> FloatArray:
    """Seconds to charge from `level` units to full (CC-CV), one sample per run."""
    b0 = np.clip(np.broadcast_to(np.asarray(level, dtype=float), (runs,)), 0.0, 100.0)
    rate = CHARGE_RATE * (1.0 + CHARGE_RATE_SD * rng.standard_normal(runs))
    knee = CV_KNEE + CV_KNEE_SD * rng.standard_normal(runs)
    dock = DOCK_TIME + DOCK_TIME_SD * rng.standard_normal(runs)
    t_cc = np.maximum(knee - b0, 0.0) / rate
    # CV: the gap to full decays with tau = (100 - knee) / rate (current continuous at the knee).
    tau = (100.0 - knee) / rate
    gap0 = np.minimum(100.0 - b0, 100.0 - knee)
    t_cv = tau * np.log(np.maximum(gap0 / (CUTOFF * (100.0 - knee)), 1.0))
    result: FloatArray = dock + t_cc + t_cv
    return result


def recharge(runs: int, rng: np.random.Generator) -> Outputs:
    return {"duration": recharge_time(LOW_BATTERY, runs, rng)}


_FLIGHT = {"duration": "duration", "battery": "battery"}

SIMULATORS: tuple[Simulator, ...] = (
    Simulator(
        "uav.takeoff",
        f"Spool-up and climb from the ground to {SEARCH_HEIGHT:g} m.",
        _FLIGHT,
        takeoff,
    ),
    Simulator(
        "uav.initialise",
        f"{CHECK_WINDOW:g} s hover self-test plus GNSS convergence; `fail` = a subsystem alarm.",
        {**_FLIGHT, "fail": "probability"},
        initialise,
    ),
    Simulator(
        "uav.search",
        f"Move one {CELL:g} m square at search height and capture a camera frame.",
        _FLIGHT,
        search,
    ),
    Simulator(
        "uav.approach",
        "Fly from the square's centre to above the detected object.",
        _FLIGHT,
        approach,
    ),
    Simulator(
        "uav.descend_grab",
        f"Descend from {SEARCH_HEIGHT:g} m to the grab height {GRAB_HEIGHT:g} m.",
        _FLIGHT,
        descend_grab,
    ),
    Simulator(
        "uav.grab",
        "Align over the object and close the gripper; `fail` = object not captured.",
        {**_FLIGHT, "fail": "probability"},
        grab,
    ),
    Simulator(
        "uav.ascend",
        f"Climb with the object from {GRAB_HEIGHT:g} m to {SEARCH_HEIGHT:g} m.",
        _FLIGHT,
        ascend,
    ),
    Simulator(
        "uav.transport",
        f"Carry the object one {CELL:g} m square; `drop` = the object slipped out.",
        {**_FLIGHT, "drop": "probability"},
        transport,
    ),
    Simulator(
        "uav.descend_deposit",
        f"Descend with the object to the release height {DEPOSIT_HEIGHT:g} m.",
        _FLIGHT,
        descend_deposit,
    ),
    Simulator("uav.deposit", "Hold over the deposit bin and open the gripper.", _FLIGHT, deposit),
    Simulator(
        "uav.ascend_empty",
        f"Climb without object from {DEPOSIT_HEIGHT:g} m to {SEARCH_HEIGHT:g} m.",
        _FLIGHT,
        ascend_empty,
    ),
    Simulator(
        "uav.return",
        f"Move one {CELL:g} m square at cruise speed (return to base or object).",
        _FLIGHT,
        return_move,
    ),
    Simulator(
        "uav.land",
        f"Descend from {SEARCH_HEIGHT:g} m, touch down and stop the motors.",
        _FLIGHT,
        land,
    ),
    Simulator(
        "uav.recharge",
        f"Dock and charge (CC-CV) from the low-battery threshold {LOW_BATTERY:g} units to full.",
        {"duration": "duration"},
        recharge,
    ),
)
