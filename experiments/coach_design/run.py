"""Design by gradient: the complete coach's yaw damping and primary longitudinal
stiffness chosen to maximise its linear critical speed on straight track while the wear
number of its worst wheel in a 600 m curve stays at or below the coach's as shipped.
Optax (Adam) on the critical speed, each step projected onto the wear constraint
linearised about the current design (the gradient projection method), both gradients
exact (implicit differentiation of the critical speed's crossing and of the steady
curving state); then a brute-force grid over the same box confirms the optimum.

The coach: `jaxrail/vehicles/data/coach.toml` (the Manchester benchmark vehicle 1),
S1002 on UIC60 1:40, friction 0.4, the contact table. Critical speed: ideal straight
track. Wear: the steady curving state (jaxrail.stability.curving) in a 600 m left curve
with 150 mm cant at 30 m/s (108 km/h, 80 mm cant deficiency); the wear number T gamma
of each wheel (creep forces times creepages, summed over its patches).

Variables: z = ln(p / p_shipped) for both parameters, in the box |z| <= ln 4 (a quarter
to four times the shipped value). Constraint: g(z) = W(z) / W_shipped - 1 <= 0.

Writes ``results.json`` beside this file (``--out``), phase by phase.
Usage: ``python experiments/coach_design/run.py [--steps N] [--rate R] [--grid N]
[--no-checks] [--out FILE]`` (``--grid 0``: no grid; ``--no-checks``: no central
differences).
"""

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import equinox as eqx
import numpy as np
import optax

import jaxrail

jaxrail.enable_float64()

import jax.numpy as jnp  # noqa: E402

from jaxrail.stability.critical import LinearStability  # noqa: E402
from jaxrail.stability.curving import SteadyCurving  # noqa: E402
from jaxrail.stability.curving_wear import CurvingWear  # noqa: E402
from jaxrail.track import Track, straight_track  # noqa: E402
from jaxrail.track.layout import Arc  # noqa: E402
from jaxrail.vehicles import contact_model, get_values, set_values, vehicle_from_file  # noqa: E402

YAW, KX = "yaw_damper.damping", "primary.longitudinal_stiffness"
NAMES = (YAW, KX)
FRICTION = 0.4
RADIUS, CANT, CURVE_SPEED = 600.0, 0.15, 30.0  # [m], [m], [m/s]
BOX = math.log(4.0)  # |z| <= this
BRACKET = 0.03  # relative half-width of the first bracket about a guessed critical speed
GUESS = 175.0  # [m/s] where the shipped coach's crossing is first looked for
RELATIVE_STEPS = (1e-2, 5e-3)  # central differences at the shipped values (Richardson)


def log(*args):
    print(*args, file=sys.stderr, flush=True)


class Study:
    def __init__(self):
        vehicle, params = vehicle_from_file("coach")
        params = eqx.tree_at(lambda p: p.contact.friction, params, FRICTION)
        self.vehicle, self.params = vehicle, params
        straight = straight_track(3000.0)  # the standard rails, as the arc's
        self.model = contact_model("table", vehicle, params, straight, progress=True)
        self.stability = LinearStability(vehicle, params, straight, self.model)
        arc = Track.from_segments([Arc(3000.0, RADIUS, "left", cant=CANT)])
        self.wear = CurvingWear(SteadyCurving(vehicle, params, arc, self.model), NAMES)
        self.shipped = np.asarray(get_values(vehicle, params, NAMES))
        self.curving_start = None

    def params_at(self, z):
        return set_values(self.vehicle, self.params, NAMES, self.shipped * np.exp(z))

    def critical(self, z, guess):
        """(SpeedPoint, evaluations) of the crossing near ``guess`` [m/s]."""
        params = self.params_at(z)
        low, high = guess * (1 - BRACKET), guess * (1 + BRACKET)
        for _ in range(8):
            points = self.stability.sweep([low, high], params)
            below, above = (p.eigenvalue.real for p in points)
            if below < 0.0 <= above:
                return self.stability.critical_speed(low, high, params, points=points)
            if below >= 0.0:
                low, high = low / (1 + 4 * BRACKET), low
            else:
                low, high = high, high * (1 + 4 * BRACKET)
        raise ValueError(f"no crossing found near {guess:g} m/s at z = {list(z)}")

    def critical_and_gradient(self, z, guess):
        point = self.critical(z, guess)
        gradient = self.stability.critical_speed_gradient(point, NAMES, self.params_at(z))
        # d/dz = p d/dp
        values = self.shipped * np.exp(z)
        return point, np.array([gradient[n] for n in NAMES]) * values

    def worst_wear(self, z, gradient=True):
        point = self.wear(CURVE_SPEED, self.params_at(z), start=self.curving_start)
        self.curving_start = point.state
        w = point.wear_number_n
        k = np.unravel_index(np.argmax(w), w.shape)
        values = self.shipped * np.exp(z)
        dz = np.array([point.gradient[n][k] for n in NAMES]) * values
        return float(w[k]), dz, [int(k[0]) + 1, ["left", "right"][k[1]]], point


def point_dict(p):
    return {"speed_m_s": p.speed, "frequency_hz": p.frequency_hz,
            "damping_ratio": p.damping_ratio}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--steps", type=int, default=12, help="optimiser steps")
    parser.add_argument("--rate", type=float, default=0.3,
                        help="Adam's first step size in z (decays to a tenth)")
    parser.add_argument("--grid", type=int, default=5, help="grid points per parameter")
    parser.add_argument("--no-checks", dest="checks", action="store_false")
    parser.add_argument("--out", default=str(Path(__file__).with_name("results.json")))
    args = parser.parse_args()
    start = time.perf_counter()
    out = {"experiment": "coach_design", "load_before": os.getloadavg(),
           "parameters": list(NAMES), "curve": {"radius_m": RADIUS, "cant_m": CANT,
                                                "speed_m_s": CURVE_SPEED},
           "friction": FRICTION, "box": [-BOX, BOX]}

    def save():
        out["wall_s"] = time.perf_counter() - start
        out["load_now"] = os.getloadavg()
        Path(args.out).write_text(json.dumps(out, indent=1) + "\n")

    study = Study()
    out["shipped"] = dict(zip(NAMES, study.shipped.tolist()))
    zero = np.zeros(2)
    # the shipped coach: its critical speed, its wear number
    v0 = study.critical(zero, GUESS)
    w0, dw0, wheel0, _ = study.worst_wear(zero)
    out["shipped_critical"] = point_dict(v0)
    out["shipped_wear_number_n"], out["worst_wheel"] = w0, wheel0
    log("shipped", point_dict(v0), w0, wheel0)
    save()

    # the gradients at the shipped values against central differences (Richardson)
    _, dv0 = study.critical_and_gradient(zero, v0.speed)
    checks = {}
    for k, name in (enumerate(NAMES) if args.checks else ()):
        estimates = {}
        for h in RELATIVE_STEPS:
            dz = np.zeros(2)
            dz[k] = math.log1p(h)
            vp, vm = (study.critical(s * dz, v0.speed).speed for s in (1.0, -1.0))
            wp, wm = (study.worst_wear(s * dz)[0] for s in (1.0, -1.0))
            estimates[h] = ((vp - vm) / (2 * dz[k]), (wp - wm) / (2 * dz[k]))
        (v1, w1), (v2, w2) = estimates[RELATIVE_STEPS[0]], estimates[RELATIVE_STEPS[1]]
        ratio = (RELATIVE_STEPS[0] / RELATIVE_STEPS[1]) ** 2
        v_rich, w_rich = (ratio * v2 - v1) / (ratio - 1), (ratio * w2 - w1) / (ratio - 1)
        checks[name] = {
            "critical_speed": {"implicit": dv0[k], "central": [v1, v2], "richardson": v_rich,
                               "relative_difference": abs(dv0[k] / v_rich - 1.0)},
            "wear_number": {"implicit": dw0[k], "central": [w1, w2], "richardson": w_rich,
                            "relative_difference": (abs(dw0[k] / w_rich - 1.0)
                                                    if w_rich != 0.0 else None),
                            "absolute_difference_n": abs(dw0[k] - w_rich)}}
        log(name, json.dumps(checks[name]))
    out["gradient_checks_per_log_parameter"] = checks
    out["gradient_check_steps"] = list(RELATIVE_STEPS)
    save()

    # optax: Adam on -V / V0; each step then moved the least distance onto the wear
    # constraint linearised about the current design, g + dg . (z' - z) <= 0, and into
    # the box
    optimiser = optax.adam(optax.exponential_decay(args.rate, args.steps, 0.1))
    z = zero.copy()
    state = optimiser.init(jnp.asarray(z))
    guess, history = v0.speed, []
    for step in range(args.steps):
        point, dv = study.critical_and_gradient(z, guess)
        w, dw, wheel, _ = study.worst_wear(z)
        g, dg = w / w0 - 1.0, dw / w0
        history.append({"step": step, "z": z.tolist(),
                        "values": (study.shipped * np.exp(z)).tolist(),
                        "critical_speed_m_s": point.speed, "wear_number_n": w,
                        "constraint": g, "critical_speed_gradient_dz": dv.tolist(),
                        "wear_gradient_dz": dw.tolist(), "worst_wheel": wheel})
        log(json.dumps(history[-1]))
        updates, state = optimiser.update(jnp.asarray(-dv / v0.speed), state)
        trial = z + np.asarray(updates)
        excess = g + dg @ (trial - z)
        if excess > 0.0:
            trial = trial - excess * dg / (dg @ dg)
        z = np.clip(trial, -BOX, BOX)
        guess = point.speed
        out["optimisation"] = history
        save()
    point, dv = study.critical_and_gradient(z, guess)
    w, dw, wheel, _ = study.worst_wear(z)
    out["optimum"] = {"z": z.tolist(), "values": dict(zip(NAMES, (study.shipped * np.exp(z))
                                                          .tolist())),
                      "critical": point_dict(point), "wear_number_n": w,
                      "constraint": w / w0 - 1.0,
                      "critical_speed_gradient_dz": dv.tolist(), "wear_gradient_dz": dw.tolist()}
    log("optimum", json.dumps(out["optimum"]))
    save()

    if args.grid < 2:
        return
    # brute force: the grid over the box
    axis = np.linspace(-BOX, BOX, args.grid)
    wear_by_k = {}
    for j, zk in enumerate(axis):
        wear_by_k[j] = study.worst_wear(np.array([0.0, zk]))[0]
    grid = []
    guess = v0.speed
    for j, zk in enumerate(axis):
        row_guess = guess
        for i, zc in enumerate(axis):
            zz = np.array([zc, zk])
            try:
                p = study.critical(zz, row_guess)
                speed = p.speed
                row_guess = speed
                if i == 0:
                    guess = speed
            except ValueError as error:
                speed = None
                log(str(error))
            grid.append({"z": zz.tolist(), "values": (study.shipped * np.exp(zz)).tolist(),
                         "critical_speed_m_s": speed, "wear_number_n": wear_by_k[j],
                         "feasible": wear_by_k[j] <= w0 * (1 + 1e-9)})
            log(json.dumps(grid[-1]))
            out["grid"] = grid
            save()
    feasible = [g for g in grid if g["feasible"] and g["critical_speed_m_s"] is not None]
    best = max(feasible, key=lambda g: g["critical_speed_m_s"])
    out["grid_best_feasible"] = best
    out["optimum_minus_grid_best_m_s"] = out["optimum"]["critical"]["speed_m_s"] - \
        best["critical_speed_m_s"]
    out["load_after"] = os.getloadavg()
    save()
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
