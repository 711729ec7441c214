"""Numerical verification of the stability map at A1*..A6* (paper section 3.3, Fig. 9).

For each point (g, tau) the FMU (TDVASS, road = 1 with road_amplitude = 0,
i.e. no road input) starts from X0 = [0.01, 0, 0, 0, 0, 0]
(x_s_start = 0.01 m) and the body acceleration is recorded. Each point's
spectral abscissa (real part of the rightmost characteristic root) is read
from the FMU's calculatedParameter `spectral_abscissa`. An unstable run stops
when the response passes the FMU's divergence bound (1e3 m): doStep then
fails (fmi2Discard) and the curve ends where the FMU stopped. Writes

- stability_verification.png: BA(t) at the six points (Fig. 9),
- stability_verification_envelope.png: the envelope of |BA| on a log scale
  against e^(sigma t), sigma = the spectral abscissa,
- stability_verification.txt: verdicts (paper, spectral abscissa, simulation).

    python examples/stability_verification.py [--quick] [--out out]
"""

from __future__ import annotations

import numpy as np

import _common as C

OUTPUTS = ["body_acceleration", "x_s", "x_t"]


def envelope(t: np.ndarray, y: np.ndarray, window: float) -> tuple[np.ndarray, np.ndarray]:
    """max |y| over consecutive windows of `window` seconds (centre times)."""
    if t.size < 2:
        return t, np.abs(y)
    dt = t[1] - t[0]
    n = max(1, int(round(window / dt)))
    k = y.size // n
    if k == 0:
        return t[:1], np.abs(y[:1])
    a = np.abs(y[: k * n]).reshape(k, n).max(axis=1)
    tc = t[: k * n].reshape(k, n).mean(axis=1)
    return tc, a


def main() -> None:
    p = C.parser(__doc__.splitlines()[0])
    p.add_argument("--fmu", default=None, help="FMU path (default $TDVASS_FMU or target/fmu/tdvass.fmu)")
    p.add_argument("--duration", type=float, default=25.0,
                   help="simulated time (s); long enough for all three unstable points to diverge")
    p.add_argument("--step", type=float, default=None,
                   help="communication step (s); default 0.002 (0.01 with --quick)")
    args = p.parse_args()
    out = C.prepare_out(args.out)
    duration = args.duration
    step = args.step or (0.01 if args.quick else 0.002)

    def read_stability(fmu):
        sa = fmu.get("spectral_abscissa") if fmu.has("spectral_abscissa") else float("nan")
        st = bool(fmu.get("stable")) if fmu.has("stable") else bool(sa < 0)
        return sa, st

    runs = []
    with C.FmuRunner(args.fmu) as fmu:
        for label, g, tau, paper_stable in C.STABILITY_POINTS:
            params = {"variant": 3, "road": 1, "road_amplitude": 0.0, "g": g, "tau": tau,
                      "x_s_start": 0.01, "v_s_start": 0.0, "x_h_start": 0.0, "v_h_start": 0.0,
                      "x_t_start": 0.0, "v_t_start": 0.0}
            r = fmu.run(params, duration, step, OUTPUTS, after_init=read_stability)
            sa, stable = r["extra"]
            runs.append(dict(label=label, g=g, tau=tau, paper=paper_stable, sa=sa, stable=stable, r=r))
            stop = f"stopped at t = {r['time'][-1]:.3f} s" if r["error"] else "ran to the end"
            print(f"{label}: g = {g:+g}, tau = {tau:g}: spectral abscissa {sa:+.4f} 1/s, {stop}")

    def sim_verdict(run):
        """stable / unstable from the simulation alone: diverged, or |BA| envelope grows."""
        r = run["r"]
        if r["error"]:
            return False
        tc, env = envelope(r["time"], r["body_acceleration"], 1.0)
        half = env.size // 2
        return bool(env[half:].max() < env[:half].max())

    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 2, figsize=(13, 10), constrained_layout=True)
    # paper layout: stable points on the left, unstable on the right
    order = [r for r in runs if r["paper"]] + [r for r in runs if not r["paper"]]
    for idx, run in enumerate(order):
        ax = axes[idx % 3, idx // 3]
        r = run["r"]
        color = "tab:blue" if run["stable"] else "tab:red"
        ax.plot(r["time"], r["body_acceleration"], color=color, lw=0.6)
        verdict = "stable" if run["stable"] else "unstable"
        ax.set_title(f"{run['label']}: g = {run['g']:+.0f} N/m, τ = {run['tau']:g} s — {verdict}, "
                     f"σ = {run['sa']:+.3f} 1/s", fontsize=10)
        if r["error"]:
            ax.axvline(r["time"][-1], color="k", ls=":", lw=1)
            ax.annotate(f"diverged (> 1e3 m):\nFMU stopped at t = {r['time'][-1]:.2f} s",
                        (r["time"][-1], 0), xytext=(-8, 0), textcoords="offset points",
                        ha="right", va="center", fontsize=8.5,
                        bbox=dict(boxstyle="round", fc="white", ec="0.6"))
        ax.set_xlim(0, duration)
        ax.set_ylabel("BA (m/s²)")
        ax.grid(True, alpha=0.3)
        if idx % 3 == 2:
            ax.set_xlabel("time t (s)")
        lim = np.nanmax(np.abs(r["body_acceleration"]))
        ax.set_ylim(-1.1 * lim, 1.1 * lim)
    fig.suptitle("Stability verification (paper Fig. 9): TDVASS, no road input, X0 = [0.01, 0, 0, 0, 0, 0]; "
                 "body acceleration\nleft: points the paper calls stable, right: unstable; "
                 "σ = spectral abscissa from the FMU; fmpy + tdvass.fmu")
    C.save_figure(fig, out, "stability_verification")

    fig, ax = plt.subplots(figsize=(11, 7), layout="constrained")
    cmap = plt.get_cmap("tab10")
    for i, run in enumerate(runs):
        r = run["r"]
        tc, env = envelope(r["time"], r["body_acceleration"], 1.0)
        c = cmap(i)
        ax.semilogy(tc, env, color=c, lw=1.6,
                    label=f"{run['label']} (g = {run['g']:+.0f}, τ = {run['tau']:g}): σ = {run['sa']:+.3f} 1/s")
        # reference slope e^(sigma t) through the envelope at 60 % of the run
        j = int(0.6 * (env.size - 1))
        if env.size > 2 and np.isfinite(run["sa"]):
            ax.semilogy(tc, env[j] * np.exp(run["sa"] * (tc - tc[j])), color=c, ls="--", lw=1)
        if r["error"]:
            ax.plot(r["time"][-1], env[-1], "x", color=c, ms=10, mew=2)
    ax.plot([], [], "k--", lw=1, label="reference e^(σ t)")
    ax.plot([], [], "kx", ms=8, mew=2, ls="none", label="FMU stopped: divergence bound 1e3 m")
    ax.set_xlabel("time t (s)")
    ax.set_ylabel("envelope of |BA|: max over 1 s windows (m/s²)")
    ax.set_xlim(0, duration)
    ax.set_title("Growth and decay of the body acceleration at A1*..A6* against the rightmost root "
                 "(TDVASS, X0 = [0.01, 0, 0, 0, 0, 0])", fontsize=10.5)
    ax.grid(True, which="both", alpha=0.3)
    fig.legend(*ax.get_legend_handles_labels(), fontsize=8.5, loc="outside lower center", ncol=3)
    C.save_figure(fig, out, "stability_verification_envelope")

    lines = [f"Stability verification (section 3.3): TDVASS, no road, X0 = [0.01, 0, 0, 0, 0, 0], "
             f"{duration:g} s, communication step {step:g} s",
             "", f"{'point':<6}{'g (N/m)':>9}{'tau (s)':>8}{'paper':>10}{'sigma (1/s)':>13}{'root':>10}"
                 f"{'simulation':>12}  run"]
    agree = True
    for run in runs:
        r = run["r"]
        sim = sim_verdict(run)
        agree &= (run["paper"] == run["stable"] == sim)
        how = (f"diverged, FMU stopped at t = {r['time'][-1]:.3f} s" if r["error"]
               else f"ran {r['time'][-1]:g} s, max |BA| {np.nanmax(np.abs(r['body_acceleration'])):.3g} m/s^2")
        lines.append(f"{run['label']:<6}{run['g']:>9.0f}{run['tau']:>8.2f}"
                     f"{'stable' if run['paper'] else 'unstable':>10}{run['sa']:>+13.4f}"
                     f"{'stable' if run['stable'] else 'unstable':>10}{'stable' if sim else 'unstable':>12}  {how}")
    lines.append(f"paper, rightmost root and simulation agree at all six points: {'yes' if agree else 'NO'}")
    C.write_summary(out, "stability_verification", "\n".join(lines))


if __name__ == "__main__":
    main()
