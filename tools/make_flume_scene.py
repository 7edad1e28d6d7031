#!/usr/bin/env python3
"""Write a Denlinger-style sand flume scene (docs/flume.md): an inclined plane, a circular transition
and a horizontal runout plane, with a sand wedge at rest behind a bed-normal gate.

    python3 tools/make_flume_scene.py > inputs/denlinger_flume.json                 # the defaults
    python3 tools/make_flume_scene.py --slope 30 --bed-friction 27 --name denlinger_flume_abe2005 \
        > inputs/denlinger_flume_abe2005.json                                       # Abe, Johansson & Konagai's (2005) set
    python3 tools/make_flume_scene.py --cell 0.01 --name flume_h010 > /tmp/flume_h010.json  # resolution study
    python3 tools/make_flume_scene.py --separation-volume-ratio 1.05 --name denlinger_flume_recompacting > inputs/denlinger_flume_recompacting.json

Geometry (x down-flume, z up, y across; the runout plane is z = 0, the gate foot is x = 0):
  gate foot A on the bed; the gate is the bed normal through A;
  the slope runs `--slope-length` (1.2 m) from A to the start of the transition, a circular arc of
  radius `--radius` (0.2 m) tangent to the slope and to the runout plane, which runs `--runout-length`
  (1.2 m) from the end of the arc. The slope continues `--headroom` (0.1 m) up behind the wedge.
  The wedge: the triangle A, B = A + L (-cos t, sin t) (L = `--wedge-length` along the bed, 0.25 m) and
  C = A + L tan t (sin t, cos t) on the gate, so the free surface BC is horizontal; it spans
  `--wedge-width` (0.2 m) across the centre of the `--width` (0.6 m) plane.
The grid follows the terrain (third coordinate w = z - z_b(x), the z- face is the bed).
"""
import argparse
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # for cli_checks, next to this script
from cli_checks import refuse  # noqa: E402

DEFAULT_HEIGHT = 0.3


def material(a):
    """The sand: Drucker-Prager (the default), or mu(I) (docs/flume.md, "The flume with mu(I)"): mu_s = tan of
    the internal friction angle, the rise mu_2 - mu_s = 0.2616 and I0 = 0.279 of Jop, Forterre & Pouliquen 2006."""
    if a.model == "mu_i":
        mu_s = round(math.tan(math.radians(a.friction)), 6)
        return {"model": "mu_i", "density": a.density, "young": 2.0e6, "poisson": 0.3,
                "mu_s": mu_s, "mu_2": round(mu_s + a.mu_rise, 6), "i0": a.i0,
                "grain_diameter": a.grain_diameter, "grain_density": a.grain_density,
                "separation_volume_ratio": a.separation_volume_ratio}
    sand = {"model": "drucker_prager", "density": a.density, "young": 2.0e6, "poisson": 0.3,
            "friction_angle": a.friction, "dilatancy_angle": 0.0, "cohesion": 10.0,
            "hardening_modulus": 0.0, "kinematic_fraction": 0.2, "cone": "plane_strain"}
    if a.separation_volume_ratio != 1.5:  # the default scenes leave talus's default unnamed, as they always did
        sand["separation_volume_ratio"] = a.separation_volume_ratio
    return sand


def wedge_height(a):
    """The wedge's height above the bed at the top of the gate (x = C_x), which the grid's height must
    exceed 1.5 times (build()'s w_top)."""
    t = math.radians(a.slope)
    return a.wedge_length * math.tan(t) / math.cos(t)


def wedge_overhang(a, slope):
    """How far the wedge's top at the gate (C) lies beyond the end of build()'s grid along x [m]
    (negative: inside). C moves down-flume as the slope steepens: from about 81 degrees on (the
    default lengths) it lies beyond the runout plane, and talus refuses the scene."""
    t = math.radians(slope)
    h = a.cell
    tangent = a.radius * math.tan(t / 2)
    along = a.slope_length + tangent
    end_x = along * math.cos(t) + tangent + a.runout_length
    x0 = math.floor(-(a.wedge_length + a.headroom) * math.cos(t) / h) * h
    x1 = x0 + math.ceil((end_x - x0) / h - 1e-9) * h
    return a.wedge_length * math.tan(t) * math.sin(t) - x1


def steepest_slope(a):
    """The steepest slope [deg] whose wedge lies inside build()'s grid (bisection; 2 decimals, down)."""
    lo, hi = 0.0, 90.0 - 1e-9
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if wedge_overhang(a, mid) <= 0 else (lo, mid)
    return math.floor(lo * 100) / 100


def build(a):
    t = math.radians(a.slope)
    h = a.cell
    tangent = a.radius * math.tan(t / 2)                 # fillet tangent length
    along = a.slope_length + tangent                     # gate foot -> slope/runout vertex, along the bed
    ax, az = 0.0, along * math.sin(t)                    # gate foot A; the vertex V is at z = 0
    vx = along * math.cos(t)
    end_x = vx + tangent + a.runout_length               # end of the runout plane
    up = a.wedge_length + a.headroom                     # slope behind the gate
    x0 = math.floor((ax - up * math.cos(t)) / h) * h     # grid origin on a whole cell
    nx = math.ceil((end_x - x0) / h - 1e-9)
    x1 = x0 + nx * h
    bed = lambda x: az - (x - ax) * math.tan(t)           # the slope line
    d = a.wedge_length * math.tan(t)                     # wetted gate height (bed normal)
    A = (ax, az)
    B = (ax - a.wedge_length * math.cos(t), az + a.wedge_length * math.sin(t))
    C = (ax + d * math.sin(t), az + d * math.cos(t))
    w_top = d / math.cos(t)                              # the wedge's height above the bed at x = C_x
    nw = math.ceil(max(a.height, 1.5 * w_top) / h - 1e-9)  # (main refuses a --height below 1.5 w_top)
    ny = math.ceil(a.width / h - 1e-9)
    r6 = lambda v: round(v, 6)
    mu = math.tan(math.radians(a.bed_friction))
    mass = 0.5 * a.wedge_length * d * a.wedge_width * a.density
    scene = {
        "name": a.name,
        "description": (f"Denlinger-style dry sand flume (docs/flume.md): {a.slope} deg slope, {a.slope_length} m gate to "
                        f"transition, transition radius {a.radius} m, {a.runout_length} m runout plane, {a.width} m wide "
                        f"with open sides; a {a.wedge_length} m x {a.wedge_width} m sand wedge ({mass:.2f} kg) behind a "
                        f"bed-normal gate removed at t = 0; internal friction {a.friction} deg, bed friction {a.bed_friction} deg"
                        + ("; mu(I) sand, mu_s = tan(internal friction)" if a.model == "mu_i" else "")
                        + (f"; separation_volume_ratio {a.separation_volume_ratio:g} (loosened sand re-compacts)"
                           if a.separation_volume_ratio != 1.5 else "")),
        "comment": "written by tools/make_flume_scene.py " + " ".join(sys.argv[1:]),
        "grid": {
            "origin": [r6(x0), r6(-ny * h / 2), 0.0],
            "size": [r6(nx * h), r6(ny * h), r6(nw * h)],
            "cell_size": h,
            "terrain": {"points": [[r6(x0), r6(bed(x0))], [r6(vx), 0.0], [r6(x1), 0.0]],
                        "radii": [0.0, a.radius, 0.0]},
        },
        "gravity": [0.0, 0.0, -9.81],
        "time": {"end": a.end, "courant": 0.3},
        "solver": dict({"scheme": "musl", "shape": a.shape, "pic_fraction": a.pic_fraction},
                       **({"scatter": a.scatter} if a.scatter != "colour_passes" else {})),
        "materials": {"sand": material(a)},
        "bodies": [{
            "name": "wedge", "material": "sand",
            "prism": {"points": [[r6(A[0]), r6(A[1])], [r6(C[0]), r6(C[1])], [r6(B[0]), r6(B[1])]],
                      "y": [r6(-a.wedge_width / 2), r6(a.wedge_width / 2)]},
            "particles_per_cell": a.particles_per_cell,
        }],
        "boundaries": {
            "x-": "slip", "x+": "open", "y-": "open", "y+": "open",
            "z-": {"type": "friction", "friction_coefficient": mu},
            "z+": "open",
        },
        "output": {"frame_interval": a.frame_interval, "history_interval": 0.01, "compression": "lz4"},
        "diagnostics": {"runout": {"gate_x": 0.0, "runout_plane_x": r6(vx + tangent), "deposit_cell": 2 * h}},
    }
    return scene


def sentence(text):
    """text with its first letter in upper case (str.capitalize would lower the rest)."""
    return text[:1].upper() + text[1:]


def flat_slope(a):
    """The same wedge on an endless inclined plane, in coordinates along (x) and normal to (z) the bed."""
    t = math.radians(a.slope)
    h = a.cell
    scene = build(a)
    d = a.wedge_length * math.tan(t)
    x0 = -math.ceil((a.wedge_length + a.headroom) / h) * h
    nx = math.ceil((a.slope_length - x0) / h)
    g = scene["grid"]
    g.pop("terrain")
    g["origin"][0] = round(x0, 6)
    g["size"][0] = round(nx * h, 6)
    scene["name"] += "_flat_slope"
    scene["description"] = (f"The wedge of the Denlinger-style flume (docs/flume.md) on an endless plane inclined at "
                            f"{a.slope} deg, in coordinates along (x) and normal to (z) the bed: no transition, no runout "
                            f"plane. " + sentence(scene["description"].split("; ", 1)[1]))
    scene["gravity"] = [9.81 * math.sin(t), 0.0, -9.81 * math.cos(t)]
    scene["bodies"][0]["prism"]["points"] = [[0.0, 0.0], [0.0, round(d, 6)], [round(-a.wedge_length, 6), 0.0]]
    scene["diagnostics"]["runout"] = {"gate_x": 0.0, "deposit_cell": 2 * h}
    return scene


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--name", default="denlinger_flume")
    p.add_argument("--slope", type=float, default=31.4, help="slope angle [deg] (experiment: 31.4, Abe, Johansson & Konagai 2005: 30)")
    p.add_argument("--bed-friction", type=float, default=29.0, help="bed friction angle [deg] (29; Abe, Johansson & Konagai 2005: 27)")
    p.add_argument("--friction", type=float, default=40.0, help="internal friction angle [deg] (mu(I): mu_s = its tangent)")
    p.add_argument("--model", default="drucker_prager", choices=["drucker_prager", "mu_i"], help="the sand's material model")
    p.add_argument("--mu-rise", type=float, default=0.2616,
                   help="mu(I): mu_2 - mu_s (Jop, Forterre & Pouliquen 2006: tan 32.76 deg - tan 20.9 deg)")
    p.add_argument("--i0", type=float, default=0.279, help="mu(I): I0 (Jop, Forterre & Pouliquen 2006)")
    p.add_argument("--grain-diameter", type=float, default=0.5e-3, help="mu(I): grain diameter [m]")
    p.add_argument("--grain-density", type=float, default=2650.0, help="mu(I): grain density [kg/m^3] (quartz)")
    p.add_argument("--density", type=float, default=1600.0)
    p.add_argument("--separation-volume-ratio", type=float, default=1.5,
                   help="V/V0 beyond which a particle is stress-free (materials.<name>.separation_volume_ratio; "
                        "1.05 re-compacts the deposit: docs/flume.md, 'The sand loosens as it flows')")
    p.add_argument("--slope-length", type=float, default=1.2, help="gate to the start of the transition [m]")
    p.add_argument("--radius", type=float, default=0.2, help="transition radius [m]")
    p.add_argument("--runout-length", type=float, default=1.2, help="runout plane length [m]")
    p.add_argument("--width", type=float, default=0.6, help="plane width [m]")
    p.add_argument("--wedge-length", type=float, default=0.25, help="wedge length along the bed [m]")
    p.add_argument("--wedge-width", type=float, default=0.2, help="wedge width [m]")
    p.add_argument("--headroom", type=float, default=0.1, help="slope behind the wedge [m]")
    p.add_argument("--height", type=float, default=None,
                   help=f"grid height above the bed [m] (default {DEFAULT_HEIGHT}, raised to 1.5x the wedge's height "
                        "above the bed at the gate where that is more; a smaller --height is refused)")
    p.add_argument("--cell", type=float, default=0.0125, help="cell size [m]")
    p.add_argument("--particles-per-cell", type=int, default=2, help="n: n^3 particles per cell")
    p.add_argument("--end", type=float, default=4.0, help="end time [s]")
    p.add_argument("--pic-fraction", type=float, default=0.01,
                   help="PIC share of the G2P update (solver.pic_fraction): 0.01 lets the deposit come to rest")
    p.add_argument("--frame-interval", type=float, default=0.05)
    p.add_argument("--shape", default="linear", choices=["linear", "ugimp", "cpgimp", "bspline2"],
                   help="shape function (solver.shape); linear is the fast default, bspline2 the more accurate "
                        "(docs/flume.md, 'Thin spots')")
    p.add_argument("--scatter", default="colour_passes", choices=["colour_passes", "block_buffers"],
                   help="solver.scatter: block_buffers for many threads (docs/performance.md 'Scaling')")
    p.add_argument("--flat-slope", action="store_true",
                   help="no terrain: the slope alone in bed-aligned coordinates with gravity tilted (runs without "
                        "the terrain grid; for timing and checks)")
    a = p.parse_args()
    for option, value in vars(a).items():  # (--end inf wrote "Infinity", which is no JSON)
        if isinstance(value, float) and not math.isfinite(value):
            refuse(f"--{option.replace('_', '-')}", value, "give a finite number")
    # (--cell 0 divided by zero; negative sizes wrote scenes that talus refused)
    for option in ("wedge_width", "height", "cell", "end"):
        if option == "height" and a.height is None:
            continue
        if not getattr(a, option) > 0:
            p.error(f"--{option.replace('_', '-')} = {getattr(a, option)} must be positive")
    for option in ("wedge_length", "slope_length", "runout_length"):  # (-0.1 wrote a wedge talus refused)
        if not getattr(a, option) > 0:
            refuse(f"--{option.replace('_', '-')}", f"{getattr(a, option):g}", "give more than 0 m")
    for option in ("headroom", "radius", "frame_interval"):  # frame_interval 0: the first and last frame (talus)
        if getattr(a, option) < 0:
            refuse(f"--{option.replace('_', '-')}", f"{getattr(a, option):g}", "give 0 or more")
    if not 0 < a.friction < 90:
        refuse("--friction", f"{a.friction:g}", "give more than 0 and less than 90 degrees")
    # the bed's friction_coefficient is tan(--bed-friction), which talus takes in [0, 100] (95 gave a negative one)
    steepest = math.floor(math.degrees(math.atan(100.0)) * 100) / 100
    if not 0 <= a.bed_friction <= steepest:
        refuse("--bed-friction", f"{a.bed_friction:g}", f"give 0 to {steepest:g} degrees (its tangent, the bed's "
               "friction_coefficient, at most 100)")
    if not 0 < a.slope < 90:  # (0, 90 and beyond wrote scenes that talus refused)
        p.error(f"--slope = {a.slope} must be between 0 and 90 degrees")
    if not (a.separation_volume_ratio > 1 or a.separation_volume_ratio == 0):
        p.error(f"--separation-volume-ratio = {a.separation_volume_ratio} must be above 1, or 0 (off)")
    if a.model == "mu_i" and a.density > a.grain_density:  # (talus refuses a packing denser than its grains)
        refuse("--density", f"{a.density:g}", f"give at most --grain-density {a.grain_density:g} kg/m^3 for --model mu_i")
    if a.particles_per_cell < 1:
        p.error(f"--particles-per-cell = {a.particles_per_cell} must be at least 1")
    # (each of these wrote a scene: a lower --height was raised without a word, a plane narrower than
    # the wedge and a wedge beyond the grid's end were refused by talus)
    if a.width < a.wedge_width - 1e-9:
        refuse("--width", f"{a.width:g}", f"give at least the wedge's width (--wedge-width {a.wedge_width:g}) in m")
    if not a.flat_slope and wedge_overhang(a, a.slope) > 0:
        refuse("--slope", f"{a.slope:g}", f"give more than 0 and at most {steepest_slope(a):g} degrees with these "
               "lengths: steeper, the wedge's top at the gate lies beyond the end of the runout plane")
    least = 1.5 * wedge_height(a)
    if a.height is None:
        a.height = max(DEFAULT_HEIGHT, least)
    elif a.height < least - 1e-9:
        refuse("--height", f"{a.height:g}", f"give at least {math.ceil(least * 1e4) / 1e4:g} m, 1.5 x the wedge's height above the bed "
               f"at the gate ({wedge_height(a):.4g} m for --slope {a.slope:g}, --wedge-length {a.wedge_length:g})")
    scene = flat_slope(a) if a.flat_slope else build(a)
    # One line per key below the top level keeps the file short and diffable.
    lines = [f'  {json.dumps(k)}: {json.dumps(v)}' for k, v in scene.items()]
    sys.stdout.write("{\n" + ",\n".join(lines) + "\n}\n")


if __name__ == "__main__":
    main()
