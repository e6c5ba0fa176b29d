"""Figures for docs/creep-forces.md: Kalker coefficients and Polach creep-force curves.

Run: python experiments/creep_forces/make_figures.py   (writes docs/figures/creep_*.png)
"""

import pathlib

import jax
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import jaxrail  # noqa: E402
from jaxrail.contact.kalker import (  # noqa: E402
    TABLE,
    TABLE_A_OVER_B,
    kalker_asymptotes,
    kalker_coefficients,
)
from jaxrail.contact.polach import PolachParameters, polach  # noqa: E402

OUT = pathlib.Path(__file__).resolve().parents[2] / "docs" / "figures"
DPI = 85
Q, MU, G, NU = 8.0e4, 0.4, 8.2e10, 0.28
A, B = 6.0e-3, 4.0e-3  # semi-axes of a typical tread contact [m]


def contact_linrol(a_over_b, nu):
    """CONTACT's linrol for comparison: linear in g = min(a/b, b/a), asymptotes below
    g = 0.101 (NumPy port of the logic, for the plot only)."""
    out = []
    for r in np.atleast_1d(a_over_b):
        g = r if r <= 1 else 1 / r
        if g < 0.101:
            out.append(np.array(kalker_asymptotes(r, nu)))
            continue
        rows = TABLE[:10] if r <= 1 else TABLE[9:][::-1]  # rows at g = 0.1 ... 1.0
        irow = int(10 * g - 0.005)
        fac = 10 * g - irow
        c = fac * rows[min(irow, 9)] + (1 - fac) * rows[irow - 1]
        w = np.array([8 * (nu - 0.25) * (nu - 0.5), -16 * (nu - 0.5) * nu, 8 * nu * (nu - 0.25)])
        out.append(1.0 / ((1.0 / c) @ w))
    return np.array(out).T


def fig_kalker():
    r = np.geomspace(0.02, 50, 400)
    ours = np.array(jax.jit(kalker_coefficients)(r, NU))
    theirs = contact_linrol(r, NU)
    asym_lo = np.array(jax.vmap(kalker_asymptotes, (0, None))(r[r < 0.3], NU))
    asym_hi = np.array(jax.vmap(kalker_asymptotes, (0, None))(r[r > 3], NU))
    nodes = np.array(jax.jit(kalker_coefficients)(TABLE_A_OVER_B, NU))
    fig, axes = plt.subplots(1, 3, figsize=(10.5, 3.3))
    for k, (ax, name) in enumerate(zip(axes, ("c11", "c22", "c23"))):
        ax.loglog(r, theirs[k], color="0.6", lw=2.5, label="CONTACT (linear, asymptote < 0.101)")
        ax.loglog(r, ours[k], "C0", lw=1.2, label="jaxrail (C2 spline + joined asymptotes)")
        ax.loglog(r[r < 0.3], asym_lo[k], "C3--", lw=0.9, label="asymptotes")
        ax.loglog(r[r > 3], asym_hi[k], "C3--", lw=0.9)
        ax.plot(TABLE_A_OVER_B, nodes[k], "k.", ms=4, label="table rows (nu = 0.28)")
        ax.set_xlabel("a/b")
        ax.set_title(f"{name}, nu = {NU}")
        ax.axvspan(0.1, 10, color="0.95", zorder=0)
    axes[0].legend(fontsize=6.5, loc="upper left")
    fig.tight_layout()
    fig.savefig(OUT / "creep_kalker.png", dpi=DPI)
    plt.close(fig)

    # zoom on the join at a/b = 0.1 (c23): CONTACT jumps, jaxrail is smooth
    r = np.linspace(0.06, 0.16, 300)
    fig, ax = plt.subplots(figsize=(4.2, 3.0))
    ax.plot(r, contact_linrol(r, NU)[2], color="0.6", lw=2.5, label="CONTACT linrol")
    ax.plot(r, np.array(jax.jit(kalker_coefficients)(r, NU))[2], "C0", label="jaxrail")
    ax.set_xlabel("a/b")
    ax.set_ylabel("c23")
    ax.set_title("join of table and asymptote, nu = 0.28", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(OUT / "creep_kalker_join.png", dpi=DPI)
    plt.close(fig)


polach_batch = jax.jit(jax.vmap(polach, (None, None, None, None, 0, 0, 0)))


def fig_spin():
    eta = np.linspace(-0.01, 0.01, 401)
    fig, axes = plt.subplots(1, 2, figsize=(9.5, 3.4))
    for psi in (-2.0, -0.5, 0.0, 0.5, 2.0):
        fx, fy = polach_batch(Q, MU, A, B, 0 * eta, eta, np.full_like(eta, psi))
        axes[0].plot(eta * 1e3, np.array(fy) / (MU * Q), label=f"phi = {psi:+.1f} 1/m")
    axes[0].set_xlabel("lateral creepage eta [1e-3]")
    axes[0].set_ylabel("Fy / (mu Q)")
    axes[0].set_title("Fy(eta) at xi = 0 for several spins", fontsize=9)
    axes[0].legend(fontsize=7)
    axes[0].axhline(0, color="0.8", lw=0.6)
    psi = np.linspace(-8, 8, 401)
    _, fy = polach_batch(Q, MU, A, B, 0 * psi, 0 * psi, psi)
    c23 = float(kalker_coefficients(A / B, NU)[2])
    axes[1].plot(psi, np.array(fy) / (MU * Q), label="Polach, pure spin")
    lin = psi[np.abs(psi) < 1.5]
    axes[1].plot(lin, -G * (A * B) ** 1.5 * c23 * lin / (MU * Q), "k--", lw=0.8, label="Kalker linear")
    axes[1].set_xlabel("spin phi [1/m]")
    axes[1].set_ylabel("Fy / (mu Q)")
    axes[1].set_title("pure spin: linear, then falling", fontsize=9)
    axes[1].legend(fontsize=7)
    fig.suptitle(f"Q = {Q / 1e3:.0f} kN, mu = {MU}, a = {A * 1e3:.0f} mm, b = {B * 1e3:.0f} mm", fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT / "creep_spin.png", dpi=DPI)
    plt.close(fig)


def fig_ellipse():
    xi = np.linspace(0, 0.01, 301)
    area = A * B
    fig, axes = plt.subplots(1, 2, figsize=(9.5, 3.4))
    for ratio in (0.2, 0.5, 1.0, 2.0, 5.0):
        a = np.sqrt(area * ratio)
        b = area / a
        fx, _ = polach_batch(Q, MU, a, b, xi, 0 * xi, 0 * xi)
        _, fy = polach_batch(Q, MU, a, b, 0 * xi, xi, 0 * xi)
        axes[0].plot(xi * 1e3, -np.array(fx) / (MU * Q), label=f"a/b = {ratio}")
        axes[1].plot(xi * 1e3, -np.array(fy) / (MU * Q), label=f"a/b = {ratio}")
    axes[0].set_xlabel("xi [1e-3] (eta = phi = 0)")
    axes[0].set_ylabel("-Fx / (mu Q)")
    axes[1].set_xlabel("eta [1e-3] (xi = phi = 0)")
    axes[1].set_ylabel("-Fy / (mu Q)")
    axes[0].set_title("longitudinal, same area a b", fontsize=9)
    axes[1].set_title("lateral, same area a b", fontsize=9)
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(OUT / "creep_ellipse.png", dpi=DPI)
    plt.close(fig)


def fig_polach2005():
    xi = np.linspace(0, 0.12, 401)
    fig, ax = plt.subplots(figsize=(5.6, 3.5))
    cases = [
        ("1999, mu = 0.55", None, 0.55, 30.0, "k"),
        ("2005 dry, V = 10 m/s", PolachParameters.dry(), 0.55, 10.0, "C0"),
        ("2005 dry, V = 30 m/s", PolachParameters.dry(), 0.55, 30.0, "C0"),
        ("2005 wet, V = 30 m/s", PolachParameters.wet(), 0.30, 30.0, "C1"),
    ]
    for label, params, mu0, speed, color in cases:
        def fx_of(x, params=params, mu0=mu0, speed=speed):
            kw = {} if params is None else {"parameters": params, "rolling_speed": speed}
            return polach(Q, mu0, A, B, x, 0.0, 0.0, G, NU, **kw)[0]

        fx = np.array(jax.jit(jax.vmap(fx_of))(xi))
        style = "--" if "10 m/s" in label else "-"
        ax.plot(xi * 1e2, -fx / Q, color=color, ls=style, label=label)
    ax.set_xlabel("longitudinal creepage xi [%]")
    ax.set_ylabel("-Fx / Q (adhesion coefficient)")
    ax.set_title("Polach 2005: falling friction, reduced slopes", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(OUT / "creep_polach2005.png", dpi=DPI)
    plt.close(fig)


def main():
    jaxrail.enable_float64()
    OUT.mkdir(parents=True, exist_ok=True)
    fig_kalker()
    fig_spin()
    fig_ellipse()
    fig_polach2005()
    for p in sorted(OUT.glob("creep_*.png")):
        print(p.name, p.stat().st_size // 1024, "kB")


if __name__ == "__main__":
    main()
