"""Figures and measured numbers for docs/normal-forces.md.

A mass hits a Hertzian wheel-rail contact (wheel rolling radius 0.46 m on a 0.3 m rail
crown, K_H from jaxrail.contact.hertz) and bounces off; diffrax integrates the 1-DOF
impact, and the rebound speed is read after the mass has left the contact. Writes
docs/figures/normal_*.png and prints the numbers quoted in the docs as JSON.

Run:  python experiments/normal_laws/make_figures.py
"""

import json
import pathlib

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import jaxrail  # noqa: E402

jaxrail.enable_float64()

from jaxrail.contact.hertz import hertz, hertz_coefficients, hertz_from_curvatures  # noqa: E402
from jaxrail.contact.normal import (  # noqa: E402
    Eq17,
    Flores,
    Hertz,
    HuntCrossley,
    LankaraniNikravesh,
)

FIGURES = pathlib.Path(__file__).resolve().parents[2] / "docs" / "figures"
MASS = 500.0  # kg: about half a wheelset on one contact
V_IN = 0.1  # m/s: normal impact speed
STIFFNESS = float(hertz_from_curvatures(5e4, 0.46, 0.0, 1 / 0.3).stiffness)  # N/m^1.5
T_END = 0.05  # s: contact lasts ~2-8 ms here; afterwards the speed is constant


@eqx.filter_jit
def drop(law, v_in, flipped=False, n_save=0, known_impact=True):
    """Integrate m delta'' = -f(delta, delta'); return (ts, delta, rate) or final state.

    known_impact: pass the true impact speed to the law (else the law's own fixed
    reference ``impact_velocity`` is used, as in a continuous simulation).
    """

    def rhs(t, y, args):
        delta, rate = y
        rate_seen = -rate if flipped else rate  # flipped: the rate of a signed gap
        v_ref = v_in if known_impact else None
        return jnp.stack([rate, -law.force(STIFFNESS, delta, rate_seen, v_ref) / MASS])

    t_c = 8.0 * (5 * MASS * v_in**2 / (4 * STIFFNESS)) ** 0.4 / v_in
    saveat = (
        diffrax.SaveAt(ts=jnp.linspace(0.0, t_c, n_save)) if n_save else diffrax.SaveAt(t1=True)
    )
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(rhs),
        diffrax.Tsit5(),
        0.0,
        T_END,
        1e-6,
        jnp.stack([jnp.zeros_like(v_in), v_in]),
        saveat=saveat,
        stepsize_controller=diffrax.PIDController(rtol=1e-10, atol=1e-15),
        max_steps=200000,
    )
    return sol.ts, sol.ys[:, 0], sol.ys[:, 1]


def rebound(law, v_in=V_IN, flipped=False):
    _, delta, rate = drop(law, jnp.asarray(v_in), flipped)
    assert float(delta[-1]) < 0.0, "still in contact at T_END"
    return float(-rate[-1] / v_in)


def rebound_batch(make_law, values, v_in=None):
    """Rebound ratio for a batch of laws (make_law(value)) or impact speeds (vmap)."""
    values = jnp.asarray(values)
    if v_in is None:
        fn = eqx.filter_vmap(lambda x: drop(make_law(x), jnp.asarray(V_IN)))
        _, delta, rate = fn(values)
        speeds = jnp.full_like(values, V_IN)
    else:
        fn = eqx.filter_vmap(lambda v: drop(make_law(None), v, known_impact=False))
        _, delta, rate = fn(values)
        speeds = values
    assert bool(jnp.all(delta[:, -1] < 0.0))
    return np.asarray(-rate[:, -1] / speeds)


def loops_figure():
    e = 0.7
    laws = [
        ("Hertz (elastic)", Hertz()),
        ("eq. (17), c_e = 0.7", Eq17(0.7, v0=0.01 * V_IN)),
        ("eq. (17).from_restitution(0.7)", Eq17.from_restitution(e, v0=0.01 * V_IN)),
        ("Hunt-Crossley, c_e = 0.7", HuntCrossley(e)),
        ("Lankarani-Nikravesh, c_e = 0.7", LankaraniNikravesh(e)),
        ("Flores, c_e = 0.7", Flores(e)),
    ]
    fig, axes = plt.subplots(2, 3, figsize=(9.5, 5.6), sharex=True, sharey=True)
    _, d_ref, _ = drop(Hertz(), jnp.asarray(V_IN), n_save=400)
    mask = np.asarray(d_ref) > 0
    d_ref = np.asarray(d_ref)[mask]
    for ax, (label, law) in zip(axes.ravel(), laws):
        _, delta, rate = drop(law, jnp.asarray(V_IN), n_save=600)
        delta, rate = np.asarray(delta), np.asarray(rate)
        inside = delta > 0
        force = np.asarray(law.force(STIFFNESS, delta, rate, V_IN))
        ax.plot(1e6 * d_ref, 1e-3 * STIFFNESS * d_ref**1.5, "k:", lw=1, label="K delta^1.5")
        ax.plot(1e6 * delta[inside], 1e-3 * force[inside], lw=1.6)
        e_eff = rebound(law)
        ax.set_title(f"{label}\nrebound e = {e_eff:.3f}", fontsize=8.5)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("penetration delta [um]")
    for ax in axes[:, 0]:
        ax.set_ylabel("normal force [kN]")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(
        f"Drop test: {MASS:.0f} kg at {V_IN} m/s on K = {STIFFNESS:.3g} N/m^1.5; "
        "loading is the upper branch",
        fontsize=9,
    )
    fig.tight_layout()
    fig.savefig(FIGURES / "normal_hysteresis_loops.png", dpi=80)
    plt.close(fig)


def restitution_figure(numbers):
    ce = np.linspace(0.1, 1.0, 19)
    curves = {
        "eq. (17), c_e as given": rebound_batch(lambda c: Eq17(c, v0=0.01 * V_IN), ce),
        "eq. (17).from_restitution(c_e)": rebound_batch(
            lambda c: Eq17.from_restitution(c, v0=0.01 * V_IN), ce
        ),
        "Hunt-Crossley": rebound_batch(lambda c: HuntCrossley(c, impact_velocity=V_IN), ce),
        "Lankarani-Nikravesh": rebound_batch(
            lambda c: LankaraniNikravesh(c, impact_velocity=V_IN), ce
        ),
        "Flores": rebound_batch(lambda c: Flores(c, impact_velocity=V_IN), ce),
    }
    numbers["restitution_grid"] = {k: dict(zip(np.round(ce, 3).tolist(), np.round(v, 4).tolist()))
                                   for k, v in curves.items()}
    # Impact speed vs a fixed reference (what a continuous simulation does).
    speeds = np.geomspace(1e-3, 1.0, 13)
    by_speed = {
        "eq. (17).from_restitution(0.7), v0 = 0.01": rebound_batch(
            lambda _: Eq17.from_restitution(0.7), speeds, v_in=True
        ),
        "Hunt-Crossley(0.7), ref 0.1 m/s": rebound_batch(lambda _: HuntCrossley(0.7), speeds, True),
        "Lankarani-Nikravesh(0.7), ref 0.1 m/s": rebound_batch(
            lambda _: LankaraniNikravesh(0.7), speeds, True
        ),
        "Flores(0.7), ref 0.1 m/s": rebound_batch(lambda _: Flores(0.7), speeds, True),
    }
    numbers["restitution_vs_speed"] = {
        k: dict(zip(np.round(speeds, 5).tolist(), np.round(v, 4).tolist()))
        for k, v in by_speed.items()
    }

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9.5, 3.9))
    ax1.plot([0, 1], [0, 1], "k:", lw=1, label="e_eff = c_e")
    for label, values in curves.items():
        ax1.plot(ce, values, marker=".", label=label)
    ax1.set_xlabel("nominal c_e")
    ax1.set_ylabel("measured rebound / impact speed")
    ax1.set_title("Impact at the law's reference speed", fontsize=9)
    ax1.legend(fontsize=7)
    ax1.grid(alpha=0.3)
    for label, values in by_speed.items():
        ax2.semilogx(speeds, values, marker=".", label=label)
    ax2.axhline(0.7, color="k", ls=":", lw=1)
    ax2.set_xlabel("impact speed [m/s] (law parameters fixed)")
    ax2.set_ylabel("measured restitution")
    ax2.set_title("Fixed reference speed, varying impact speed", fontsize=9)
    ax2.legend(fontsize=7)
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(FIGURES / "normal_restitution.png", dpi=80)
    plt.close(fig)


def sign_pitfall_figure(numbers):
    law = Eq17(0.5, v0=0.01 * V_IN)
    fig, axes = plt.subplots(1, 2, figsize=(8.0, 3.4), sharey=True)
    cases = ((False, "delta_dot > 0 = compression (jaxrail)"),
             (True, "rate of a signed gap passed (wrong)"))
    for ax, (flipped, label) in zip(axes, cases):
        _, delta, rate = drop(law, jnp.asarray(V_IN), flipped, n_save=600)
        delta, rate = np.asarray(delta), np.asarray(rate)
        force = np.asarray(law.force(STIFFNESS, delta, -rate if flipped else rate))
        inside = delta > 0
        e_eff = rebound(law, flipped=flipped)
        numbers[f"eq17_ce0.5_{'flipped' if flipped else 'correct'}_rebound"] = round(e_eff, 5)
        ax.plot(1e6 * delta[inside], 1e-3 * force[inside], color="C3" if flipped else "C0")
        # Arrows along the path: where the mass goes on loading and on unloading.
        idx = np.flatnonzero(inside)
        for i in (idx[len(idx) // 4], idx[3 * len(idx) // 4]):
            ax.annotate("", xy=(1e6 * delta[i + 25], 1e-3 * force[i + 25]),
                        xytext=(1e6 * delta[i], 1e-3 * force[i]),
                        arrowprops=dict(arrowstyle="-|>", color="k", lw=1.5, mutation_scale=14))
        ax.set_title(f"{label}\nrebound e = {e_eff:.3f}", fontsize=8.5)
        ax.set_xlabel("penetration delta [um]")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("normal force [kN]")
    fig.suptitle("eq. (17), c_e = 0.5: a flipped rate makes the loop run backwards (energy gain)",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(FIGURES / "normal_eq17_sign_pitfall.png", dpi=80)
    plt.close(fig)


def hertz_figure():
    ratio = np.geomspace(1e-3, 1e3, 400)
    c = hertz_coefficients(jnp.ones_like(ratio), ratio)
    fig, ax = plt.subplots(figsize=(5.0, 3.6))
    ax.loglog(ratio, np.asarray(c.a_over_c0 / c.b_over_c0), label="a/b")
    ax.loglog(ratio, np.asarray(c.a_over_c0), label="a/c0")
    ax.loglog(ratio, np.asarray(c.b_over_c0), label="b/c0")
    ax.loglog(ratio, np.asarray(c.stiffness_factor), label="K_H sqrt(A+B)/E*")
    ax.set_xlabel("B/A (lateral / longitudinal curvature sum)")
    ax.set_title("Hertz coefficients (smooth through the sphere B = A)", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(FIGURES / "normal_hertz_coefficients.png", dpi=80)
    plt.close(fig)


def main():
    FIGURES.mkdir(parents=True, exist_ok=True)
    contact = hertz(5e4, 0.5 / 0.46, 0.5 / 0.3)
    numbers = {
        "wheel_rail_50kN": {
            k: float(getattr(contact, k)) for k in ("a", "b", "approach", "stiffness", "p0")
        },
        "drop": {"mass": MASS, "v_in": V_IN, "stiffness": STIFFNESS},
    }
    # Finding 1: eq. (17) rebounds with sqrt(c_e); dependence on v0 / v_in.
    numbers["eq17_rebound"] = {
        c: round(rebound(Eq17(c, v0=0.01 * V_IN)), 5) for c in (0.3, 0.5, 0.8)
    }
    numbers["eq17_rebound_error_vs_v0"] = {
        r: round(rebound(Eq17(0.5, v0=r * V_IN)) / np.sqrt(0.5) - 1, 6)
        for r in (0.001, 0.01, 0.1, 0.3, 1.0)
    }
    # Finding 3: static penetration under eq. (17) at rest vs Hertz.
    for ce in (0.5, 0.8):
        load = 5e4
        delta_hertz = (load / STIFFNESS) ** (2 / 3)
        lo, hi = 0.5 * delta_hertz, 2 * delta_hertz  # bisection on the law itself
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if float(Eq17(ce).force(STIFFNESS, mid, 0.0)) < load else (lo, mid)
        numbers[f"eq17_static_penetration_ratio_ce{ce}"] = round(lo / delta_hertz, 5)
    # Finding 4: equivalent damping near rest for the default law and v0 = 1e-3.
    for ce, v0 in ((0.8, 0.01), (0.5, 1e-3)):
        c_eq = jax.grad(lambda r: Eq17(ce, v0).force(STIFFNESS, contact.approach, r))(0.0)
        k_lin = 1.5 * 5e4 / float(contact.approach)
        numbers[f"eq17_c_eq_ce{ce}_v0{v0}"] = {
            "c_eq": float(c_eq),
            "damping_ratio_1000kg": float(c_eq) / (2 * np.sqrt(k_lin * 1000.0)),
            "contact_mode_hz": np.sqrt(k_lin / 1000.0) / (2 * np.pi),
        }
    loops_figure()
    restitution_figure(numbers)
    sign_pitfall_figure(numbers)
    hertz_figure()
    print(json.dumps(numbers, indent=1))


if __name__ == "__main__":
    main()
