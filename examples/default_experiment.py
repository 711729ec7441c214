"""Run the FMU's default experiment with fmpy and print the Table 2 TDVASS row.

Usage: python examples/default_experiment.py [path/to/tdvass.fmu]
"""
import sys

from fmpy import simulate_fmu

PAPER = {"BA (m/s^2)": 0.3068, "SDD (m)": 0.0388, "TDD (mm)": 0.6251}


def main(fmu="target/fmu/tdvass.fmu"):
    result = simulate_fmu(
        fmu,
        output=["rms_body_acceleration", "rms_suspension_deflection", "rms_tire_deflection", "objective"],
    )
    last = result[-1]
    ours = {
        "BA (m/s^2)": last["rms_body_acceleration"],
        "SDD (m)": last["rms_suspension_deflection"],
        "TDD (mm)": last["rms_tire_deflection"] * 1e3,
    }
    print(f"TDVASS, harmonic road 0.05 sin 5t, g = 5386 N/m, tau = 2e-4 s, t = {last['time']:g} s")
    print(f"{'RMS':<12}{'tdvass':>10}{'paper':>10}")
    for name, value in ours.items():
        print(f"{name:<12}{value:>10.4f}{PAPER[name]:>10.4f}")
    print(f"{'J':<12}{last['objective']:>10.5f}")


if __name__ == "__main__":
    main(*sys.argv[1:2])
