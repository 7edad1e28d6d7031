#!/usr/bin/env python3
"""Write a planar granular column collapse scene (issue 21, item 5; docs/verification.md, "Planar
column collapse against the experiments").

    python3 tools/make_collapse_scene.py --aspect 2 --model mu_i > scene.json
    python3 tools/make_collapse_scene.py --aspect 8 --cells 10 --model dp --shape linear > scene.json

The column, L0 long and H0 = a L0 high, stands against the back wall x = 0 (slip) on a rough floor
(Coulomb friction, `--floor-friction`) and is released at rest, stress free, at t = 0: the half-column
geometry of the channel experiments (Lube et al. 2005; Balmforth & Kerswell 2005; Lajeunesse et al.
2005), one particle layer pair thick in y between slip walls (plane strain). The grid reaches beyond
the deposit that Lube et al.'s law predicts with a wide margin (`--margin` times the predicted
runout); its far end is open, so a particle that runs off is removed and counted, never piled up.

Scale: every length is a multiple of L0 (`--length`, 0.1 m) and the cell is L0 / `--cells`.
The elastic modulus is `--young-ratio` (100) times the pressure at the base of the column, rho g H0:
the elastic strain at the base is then p/M = (1+nu)(1-2nu)/((1-nu) ratio) = 0.74% for every a, and the
step count (dt = courant h / c) grows like H0/h, not faster (the runout changed by 1% between ratios
100, 400 and 1600; docs/verification.md).
End time: `--end-factor` (4.5) x sqrt(max(H0, L0)/g); the fronts measured stop moving (to 0.1%) by
about 4 sqrt(max(H0, L0)/g), and the study script reports how far each front moved over the last 10%.

Materials: Drucker-Prager (issue 21's measurement: phi = 32 deg, plane-strain cone, psi = 0,
cohesion 10 Pa) and mu(I) with the sand of docs/verification.md (`--mu-s`, `--mu-2`, `--i0`,
`--grain-diameter`, `--grain-density`): mu_s = tan 32 deg, mu_2 = mu_s + 0.2616 and I0 = 0.279 (the
rise of Jop, Forterre & Pouliquen 2006), d = 0.5 mm, quartz grains 2650 kg/m^3.
"""
import argparse
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for cli_checks, next to this script
from cli_checks import refuse  # noqa: E402

G = 9.81


def lube_runout(a):
    """(L_inf - L0)/L0 of Lube et al. 2005 for the aspect ratio a: 1.2 a below 2.3, 1.9 a^(2/3) above
    (the issue's split of their two regimes; a0 = 1.8-2.8 in the paper)."""
    return 1.2 * a if a <= 2.3 else 1.9 * a ** (2.0 / 3.0)


def build(o):
    L0 = o.length
    H0 = o.aspect * L0
    h = L0 / o.cells
    nx = math.ceil((1.0 + o.margin * lube_runout(o.aspect)) * L0 / h + 2)
    nz = math.ceil(H0 * 1.05 / h) + 2
    young = o.young_ratio * o.density * G * H0
    end = o.end_factor * math.sqrt(max(H0, L0) / G)
    r6 = lambda v: float(f"{v:.6g}")
    if o.model == "dp":
        material = {"model": "drucker_prager", "density": o.density, "young": r6(young), "poisson": o.poisson,
                    "friction_angle": o.friction_angle, "dilatancy_angle": 0.0, "cohesion": o.cohesion,
                    "hardening_modulus": 0.0, "kinematic_fraction": 0.2, "cone": "plane_strain"}
        if o.separation_volume_ratio != 1.5:  # the study's scenes leave talus's default unnamed
            material["separation_volume_ratio"] = o.separation_volume_ratio
        what = f"Drucker-Prager phi = {o.friction_angle} deg (plane-strain cone), cohesion {o.cohesion} Pa"
    else:
        material = {"model": "mu_i", "density": o.density, "young": r6(young), "poisson": o.poisson,
                    "mu_s": o.mu_s, "mu_2": o.mu_2, "i0": o.i0, "grain_diameter": o.grain_diameter,
                    "grain_density": o.grain_density, "separation_volume_ratio": o.separation_volume_ratio}
        what = f"mu(I) mu_s = {o.mu_s}, mu_2 = {o.mu_2}, I0 = {o.i0}, d = {o.grain_diameter} m"
    name = o.name or f"collapse_{o.model}_a{o.aspect:g}_n{o.cells}"
    return {
        "name": name,
        "description": (f"Planar column collapse (docs/verification.md): column L0 = {L0} m, H0 = {r6(H0)} m "
                        f"(a = {o.aspect:g}) against a slip back wall on a floor of friction {o.floor_friction}, "
                        f"cell L0/{o.cells}; {what}; E = {o.young_ratio:g} rho g H0"),
        "comment": "written by tools/make_collapse_scene.py " + o.command_line,
        "grid": {"origin": [0.0, 0.0, 0.0], "size": [r6(nx * h), r6(h), r6(nz * h)], "cell_size": r6(h)},
        "gravity": [0.0, 0.0, -G],
        "time": {"end": r6(end), "courant": 0.3},
        "solver": {"scheme": "musl", "shape": o.shape},
        "materials": {"grains": material},
        "bodies": [{"name": "column", "material": "grains",
                    "box": {"min": [0.0, 0.0, 0.0], "max": [r6(L0), r6(h), r6(H0)]},
                    "particles_per_cell": o.particles_per_cell}],
        "boundaries": {"x-": "slip", "x+": "open", "y-": "slip", "y+": "slip",
                       "z-": {"type": "friction", "friction_coefficient": o.floor_friction}, "z+": "open"},
        "output": {"frame_interval": r6(end / 10), "history_interval": r6(end / 400), "compression": "lz4"},
        "diagnostics": {"runout": {"gate_x": r6(L0), "front_quantile": o.front_quantile}},
    }


def parser():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--aspect", type=float, required=True, help="a = H0/L0")
    p.add_argument("--model", choices=["dp", "mu_i"], required=True)
    p.add_argument("--name")
    p.add_argument("--length", type=float, default=0.1, help="L0 [m]")
    p.add_argument("--cells", type=int, default=20, help="cells per L0 (h = L0/cells)")
    p.add_argument("--particles-per-cell", type=int, default=2, help="n: n^3 particles per cell")
    p.add_argument("--shape", default="cpgimp", choices=["linear", "ugimp", "cpgimp", "bspline2"])
    p.add_argument("--margin", type=float, default=2.5, help="grid length beyond L0, in Lube et al.'s runouts")
    p.add_argument("--end-factor", type=float, default=4.5, help="end time in sqrt(max(H0, L0)/g)")
    p.add_argument("--young-ratio", type=float, default=100.0, help="E / (rho g H0)")
    p.add_argument("--poisson", type=float, default=0.3)
    p.add_argument("--density", type=float, default=1600.0, help="bulk density of the packing [kg/m^3]")
    p.add_argument("--floor-friction", type=float, default=0.6, help="Coulomb friction of the floor")
    p.add_argument("--front-quantile", type=float, default=0.995, help="diagnostics.runout.front_quantile")
    p.add_argument("--separation-volume-ratio", type=float, default=1.5,
                   help="V/V0 beyond which a particle is stress-free (1.05 re-compacts the deposit: docs/flume.md, "
                        "'The sand loosens as it flows')")
    # Drucker-Prager: the measurement
    p.add_argument("--friction-angle", type=float, default=32.0)
    p.add_argument("--cohesion", type=float, default=10.0)
    # mu(I): the sand of docs/verification.md
    p.add_argument("--mu-s", type=float, default=0.6249)
    p.add_argument("--mu-2", type=float, default=0.8865)
    p.add_argument("--i0", type=float, default=0.279)
    p.add_argument("--grain-diameter", type=float, default=0.5e-3)
    p.add_argument("--grain-density", type=float, default=2650.0)
    return p


def main():
    p = parser()
    o = p.parse_args()
    for option, value in vars(o).items():  # (--aspect inf was an OverflowError; inf elsewhere wrote "Infinity")
        if isinstance(value, float) and not math.isfinite(value):
            refuse(f"--{option.replace('_', '-')}", value, "give a finite number")
    for option in ("aspect", "length", "density", "young_ratio", "end_factor"):  # (negative ones wrote refused scenes)
        if not getattr(o, option) > 0:
            p.error(f"--{option.replace('_', '-')} = {getattr(o, option)} must be positive")
    if not (o.separation_volume_ratio > 1 or o.separation_volume_ratio == 0):
        p.error(f"--separation-volume-ratio = {o.separation_volume_ratio} must be above 1, or 0 (off)")
    if o.cells < 1 or o.particles_per_cell < 1:
        p.error("--cells and --particles-per-cell must be at least 1")
    o.command_line = " ".join(sys.argv[1:])
    scene = build(o)
    lines = [f'  {json.dumps(k)}: {json.dumps(v)}' for k, v in scene.items()]
    sys.stdout.write("{\n" + ",\n".join(lines) + "\n}\n")


if __name__ == "__main__":
    main()
