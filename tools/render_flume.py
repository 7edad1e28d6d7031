#!/usr/bin/env pvpython
"""Render a flume run with ParaView: the terrain surface and the particles coloured by speed, to PNG.

    pvpython tools/render_flume.py runs/denlinger_flume --frame -1            # the last frame
    pvpython tools/render_flume.py runs/denlinger_flume --frame all           # every frame
    pvpython tools/render_flume.py runs/denlinger_flume --frame 10 --out /tmp/pngs --view side

Reads RUN_DIR/particles.pvd (the time series) and, when present, RUN_DIR/terrain.vtu (the bed, written
once for scenes with a terrain). Writes RUN_DIR/render/<view>_NNNNNN.png unless --out is given.
Frames are numbered as in the .pvd (0 = t = 0); negative numbers count from the end.

ParaView installed normally: `pvpython` (or `pvbatch`) runs this directly. Headless machines need an X
server: `xvfb-run -a pvbatch tools/render_flume.py RUN_DIR --frame -1` (Debian: packages paraview,
xvfb, xauth). On a machine with libvtk9-dev, python3-paraview conflicts with python3-vtk9; unpack it
instead: `apt-get download python3-paraview && dpkg-deb -x python3-paraview_*.deb /tmp/pv` and run
`PYTHONPATH=/tmp/pv/usr/lib/python3/dist-packages xvfb-run -a pvbatch tools/render_flume.py ...`
(docs/flume.md "Viewing a run"). Tested with ParaView 5.11 (Debian 12) that way; xvfb-run now and then
fails to start its server under load ("bad X server connection"): run it again.
"""
import argparse
import os
import sys

try:  # --help works under any Python; rendering needs ParaView's
    from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetAnimationScene, GetColorTransferFunction,
                                 GetScalarBar, PVDReader, Render, ResetCamera, SaveScreenshot, Show,
                                 XMLUnstructuredGridReader)
    HAVE_PARAVIEW = True
except ImportError:
    HAVE_PARAVIEW = False


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("run_dir")
    p.add_argument("--frame", default="-1", help="frame index (negative: from the end) or 'all'")
    p.add_argument("--out", help="folder for the PNGs (default RUN_DIR/render)")
    p.add_argument("--view", choices=["oblique", "side", "top"], default="oblique")
    p.add_argument("--size", default="1600x900", help="image size WxH")
    p.add_argument("--max-speed", type=float, default=0.0, help="top of the colour scale [m/s] (0: the frame's range)")
    a = p.parse_args()
    if not HAVE_PARAVIEW:
        sys.exit("render_flume.py: needs ParaView's Python: run it with pvpython or pvbatch (Debian package paraview)")

    pvd = os.path.join(a.run_dir, "particles.pvd")
    if not os.path.exists(pvd):
        sys.exit(f"render_flume: {pvd} not found (run `talus run SCENE --out {a.run_dir}` first)")
    out = a.out or os.path.join(a.run_dir, "render")
    os.makedirs(out, exist_ok=True)
    width, height = (int(v) for v in a.size.lower().split("x"))

    view = GetActiveViewOrCreate("RenderView")
    view.ViewSize = [width, height]
    if hasattr(view, "UseColorPaletteForBackground"):  # ParaView >= 5.10: else the palette wins
        view.UseColorPaletteForBackground = 0
    view.Background = [1.0, 1.0, 1.0]
    view.OrientationAxesVisibility = 1

    terrain_path = os.path.join(a.run_dir, "terrain.vtu")
    if os.path.exists(terrain_path):
        terrain = XMLUnstructuredGridReader(FileName=[terrain_path])
        t_display = Show(terrain, view)
        t_display.Representation = "Surface"
        t_display.ColorArrayName = ["POINTS", ""]  # plain colour, no array
        t_display.DiffuseColor = [0.78, 0.72, 0.62]
        t_display.Opacity = 0.9

    particles = PVDReader(FileName=pvd)
    p_display = Show(particles, view)
    p_display.Representation = "Points"
    p_display.PointSize = 3.0
    ColorBy(p_display, ("POINTS", "speed"))
    lut = GetColorTransferFunction("speed")
    lut.ApplyPreset("Viridis (matplotlib)", True)
    bar = GetScalarBar(lut, view)
    bar.Title = "speed [m/s]"
    bar.ComponentTitle = ""
    bar.TitleColor = [0.0, 0.0, 0.0]  # readable on the white background
    bar.LabelColor = [0.0, 0.0, 0.0]
    p_display.SetScalarBarVisibility(view, True)

    times = list(particles.TimestepValues) if particles.TimestepValues else [0.0]
    if a.frame == "all":
        frames = list(range(len(times)))
    else:
        k = int(a.frame)
        if not -len(times) <= k < len(times):
            sys.exit(f"render_flume: --frame {k} outside 0..{len(times) - 1} (or -{len(times)}..-1)")
        frames = [k % len(times)]

    view.CameraParallelProjection = 0 if a.view == "oblique" else 1
    camera = view.GetActiveCamera()
    if a.view == "side":
        camera.SetPosition(0, -10, 2.5)  # a little from above, or the bed strip is seen edge-on
        camera.SetViewUp(0, 0, 1)
    elif a.view == "top":
        camera.SetPosition(0, 0, 10)
        camera.SetViewUp(0, 1, 0)
    else:
        camera.SetPosition(3, -6, 4)
        camera.SetViewUp(0, 0, 1)
    camera.SetFocalPoint(0, 0, 0)
    ResetCamera(view)

    scene = GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    for k in frames:
        scene.AnimationTime = times[k]
        view.ViewTime = times[k]
        if a.max_speed > 0:
            lut.RescaleTransferFunction(0.0, a.max_speed)
        else:
            p_display.RescaleTransferFunctionToDataRange(False, True)
        Render(view)
        path = os.path.join(out, f"{a.view}_{k:06d}.png")
        SaveScreenshot(path, view, ImageResolution=[width, height])
        print(f"render_flume: t = {times[k]:.4g} s -> {path}")


if __name__ == "__main__":
    main()
