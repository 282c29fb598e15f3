#!/usr/bin/python3
"""Render a corocontact result off screen to PNG: one frame, or a whole series (plus an animation).

    tools/render.sh OUT/NAME.pvd --last --array von_mises --out picture.png
    tools/render.sh OUT/NAME.pvd --array velocity --out frames/      # NAME_000000.png ... + NAME.mp4
    tools/render.sh OUT/NAME_000020.vtm --array contact_depth --fade 0.2 --view xy --edges

Input: a .pvd series (every frame, or one with --frame K / --time T / --last) or a single .vtm,
.vtu or .vtp file. Every block (body) of the multiblock is drawn, coloured by --array (point or
cell data; default `displacement`, magnitude). The colour range covers the whole series by
default, so frames are comparable (--range sets it by hand); a series is drawn with one camera
that fits every frame, a single frame with a camera that fits it (--fit). A scalar bar names the
array and the simulated time is printed on the picture. --clip cuts the bodies open, --fade
and --opacity make bodies see-through (for contact_depth / contact_inside).

The README's pictures:
    tools/render.sh out/two_spheres/two_spheres.pvd --time 0.25 --array von_mises --clip z \
        --range 0 6e4 --zoom 1.15 --size 1200 750 --out docs/images/two_spheres.png --title ...
    tools/render.sh out/overlap/overlap.pvd --frame 0 --array contact_depth --range 0 0.27 \
        --fade 0.2 --zoom 1.15 --size 1200 750 --out docs/images/overlap.png --title ...

Needs Debian's python3-vtk9, so it runs under /usr/bin/python3, and an X display: without
DISPLAY it re-runs itself under `xvfb-run -a`. tools/render.sh installs what is missing
(python3-vtk9, xvfb, xauth; ffmpeg with --with-ffmpeg) and runs it under xvfb-run.

Exit codes: 0 done; 2 bad input (missing or unreadable file, unknown array, component or block,
bad frame index or time, bad option); 1 anything else (rendering or encoding failed).
"""

import argparse
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

PROG = "render.py"

# matplotlib's viridis at 17 evenly spaced points (linear RGB interpolation in between).
VIRIDIS = [
    (0.2670, 0.0049, 0.3294), (0.2823, 0.0950, 0.4173), (0.2788, 0.1755, 0.4834),
    (0.2590, 0.2515, 0.5247), (0.2297, 0.3224, 0.5457), (0.1994, 0.3876, 0.5546),
    (0.1727, 0.4488, 0.5579), (0.1490, 0.5081, 0.5572), (0.1276, 0.5669, 0.5506),
    (0.1206, 0.6258, 0.5335), (0.1579, 0.6838, 0.5017), (0.2461, 0.7389, 0.4520),
    (0.3692, 0.7889, 0.3829), (0.5160, 0.8312, 0.2943), (0.6785, 0.8637, 0.1895),
    (0.8456, 0.8873, 0.0997), (0.9932, 0.9062, 0.1439),
]
# Moreland's cool-to-warm diverging map (ParaView's default), interpolated in Msh space.
COOLWARM = [(0.2300, 0.2990, 0.7540), (0.7060, 0.0160, 0.1500)]

NO_ARRAY_COLOUR = (0.80, 0.80, 0.82)   # blocks that lack the array
TEXT_COLOUR = (0.10, 0.10, 0.12)
BG_BOTTOM = (0.80, 0.83, 0.88)
BG_TOP = (1.00, 1.00, 1.00)
VIEWS = ("iso", "xy", "xz", "yz")
AXES = {"x": 0, "y": 1, "z": 2}


class InputError(Exception):
    """A problem with what the user gave us: reported with the file it concerns, exit code 2."""

    def __init__(self, where, message):
        super().__init__(f"{where}: {message}" if where else message)


# ---------------------------------------------------------------------------------------------
# Command line


def parse_args(argv):
    p = argparse.ArgumentParser(
        prog=PROG,
        description="Render a corocontact .pvd series or a single .vtm/.vtu/.vtp off screen "
                    "to PNG.",
        epilog="Plane views: xy = x right, y up; xz = x right, z up; yz = y right, z up. "
               "Exit codes: 0 ok, 2 bad input, 1 rendering/encoding failed. "
               "tools/render.sh installs what is missing (with --with-ffmpeg also ffmpeg, for "
               "NAME.mp4) and runs this under xvfb-run.")
    p.add_argument("input", help="NAME.pvd (series) or a single .vtm, .vtu or .vtp file")
    sel = p.add_mutually_exclusive_group()
    sel.add_argument("--frame", type=int, metavar="K",
                     help="render only frame K of the .pvd (0-based; negative counts from the end)")
    sel.add_argument("--time", type=float, metavar="T",
                     help="render only the frame whose time is nearest to T")
    sel.add_argument("--last", action="store_true", help="render only the last frame")
    p.add_argument("--array", metavar="NAME",
                   help="point or cell array to colour by (default: displacement if present, "
                        "else the first array found; 'none' for plain grey)")
    p.add_argument("--component", default="magnitude", metavar="C",
                   help="magnitude (default), x, y, z or a component index")
    p.add_argument("--range", nargs=2, type=float, metavar=("MIN", "MAX"),
                   help="colour range (default: the array's range over the whole series, so "
                        "that frames are comparable)")
    p.add_argument("--fit", choices=("series", "frame"),
                   help="what the camera fits: the whole series (the default when rendering a "
                        "series: one fixed camera) or each rendered frame (the default for one "
                        "frame; for a series the camera then follows the bodies)")
    p.add_argument("--cmap", choices=("auto", "viridis", "coolwarm"), default="auto",
                   help="colour map; auto = coolwarm (centred on 0) when the array's range "
                        "straddles 0, else viridis")
    p.add_argument("--out", metavar="PATH",
                   help="PNG file for one frame; a directory for a series (default: next to the "
                        "input: NAME_<step>.png, the step of the frame shown, or the directory NAME_render/)")
    p.add_argument("--size", nargs=2, type=int, default=(1280, 800), metavar=("W", "H"),
                   help="image size in pixels (default 1280 800)")
    p.add_argument("--view", choices=VIEWS, default="iso", help="camera direction (default iso)")
    p.add_argument("--up", choices=tuple(AXES), default="y",
                   help="the axis pointing up in the iso view (default y)")
    p.add_argument("--zoom", type=float, default=1.0, help="zoom factor after fitting (default 1)")
    p.add_argument("--edges", action="store_true", help="draw the surface triangles' edges")
    p.add_argument("--opacity", action="append", default=[], metavar="[BLOCK=]VALUE",
                   help="opacity 0..1 of every block, or of one block by name (repeatable), "
                        "e.g. --opacity 0.4 --opacity ball=1 to see what lies inside other bodies")
    p.add_argument("--fade", type=float, metavar="OPACITY",
                   help="draw surfaces whose value is at the bottom of the colour range with "
                        "this opacity (0..1) and the rest opaque: e.g. --array contact_depth "
                        "--fade 0.15 shows the contact regions, also inside other bodies")
    p.add_argument("--clip", metavar="[-]AXIS[=VALUE]",
                   help="cut every body by the plane AXIS = VALUE (default: the middle of the "
                        "series' bounds) and drop the part on the + side (the - side with a "
                        "leading '-'), to show the inside, e.g. --clip z")
    p.add_argument("--blocks", metavar="A,B,...",
                   help="draw only these blocks (bodies), by name (default: all)")
    p.add_argument("--fps", type=float, default=12.0, help="animation frame rate (default 12)")
    p.add_argument("--no-animation", action="store_true",
                   help="for a series, write only the PNGs")
    p.add_argument("--title", help="text at the top left (default: the input's name)")
    a = p.parse_args(argv)
    if a.size[0] < 16 or a.size[1] < 16 or a.size[0] > 8192 or a.size[1] > 8192:
        raise InputError(None, f"--size {a.size[0]} {a.size[1]}: each side must be 16..8192 pixels")
    if a.range is not None and not a.range[0] < a.range[1]:
        raise InputError(None, f"--range {a.range[0]} {a.range[1]}: MIN must be below MAX")
    if a.fps <= 0:
        raise InputError(None, "--fps must be positive")
    if a.zoom <= 0:
        raise InputError(None, "--zoom must be positive")
    if a.fade is not None and not 0.0 <= a.fade <= 1.0:
        raise InputError(None, f"--fade {a.fade}: expected an opacity in 0..1")
    a.opacity_all, a.opacity_of = 1.0, {}
    for spec in a.opacity:
        name, eq, value = spec.rpartition("=")
        try:
            v = float(value)
        except ValueError:
            v = -1.0
        if not 0.0 <= v <= 1.0:
            raise InputError(None, f"--opacity {spec}: expected VALUE or BLOCK=VALUE with "
                                   "VALUE in 0..1")
        if eq:
            a.opacity_of[name] = v
        else:
            a.opacity_all = v
    a.clip_spec = None
    if a.clip is not None:
        spec = a.clip.strip().lower()
        sign = 1.0
        if spec.startswith(("-", "+")):
            sign, spec = (-1.0 if spec[0] == "-" else 1.0), spec[1:]
        axis, _, value = spec.partition("=")
        if axis not in AXES:
            raise InputError(None, f"--clip {a.clip}: expected x, y or z, optionally -AXIS "
                                   "and =VALUE")
        try:
            value = float(value) if value else None
        except ValueError:
            raise InputError(None, f"--clip {a.clip}: '{value}' is not a number")
        a.clip_spec = (AXES[axis], sign, value)
    return a


# ---------------------------------------------------------------------------------------------
# Series and frames


STEP_IN_NAME = re.compile(r"_(\d+)\.(vtm|vtu|vtp)$")


class Frame:
    def __init__(self, index, time, files):
        self.index = index  # position in the series
        self.time = time    # simulated time, or None when unknown
        self.files = files  # one or more .vtm/.vtu/.vtp (several when the .pvd has parts)

    def number(self):
        """The number a PNG of this frame carries: the step of corocontact's NAME_<step>.vtm, so
        NAME_000040.png shows NAME_000040.vtm; the position in the series for other files."""
        m = STEP_IN_NAME.search(os.path.basename(self.files[0]))
        return int(m.group(1)) if m else self.index


def parse_pvd(path):
    """The frames a .pvd lists, in file order; entries sharing a timestep are one frame."""
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise InputError(path, f"not a readable .pvd (XML error: {e})")
    except OSError as e:
        raise InputError(path, f"cannot read: {e.strerror}")
    if root.tag != "VTKFile" or root.get("type") != "Collection":
        raise InputError(path, "not a .pvd: expected <VTKFile type=\"Collection\">")
    base = os.path.dirname(os.path.abspath(path))
    frames, by_time = [], {}
    for ds in root.iter("DataSet"):
        f = ds.get("file")
        if not f:
            raise InputError(path, "a <DataSet> entry has no file attribute")
        ts = ds.get("timestep")
        try:
            t = float(ts) if ts is not None else None
        except ValueError:
            raise InputError(path, f"bad timestep \"{ts}\" for {f}")
        full = f if os.path.isabs(f) else os.path.join(base, f)
        key = t if t is not None else ("#", len(frames))
        if key in by_time:
            by_time[key].files.append(full)
        else:
            by_time[key] = Frame(len(frames), t, [full])
            frames.append(by_time[key])
    if not frames:
        raise InputError(path, "the series lists no datasets (has the run written a frame yet?)")
    return frames


def time_from_sibling_pvd(path):
    """The time of a single .vtm/.vtu if a .pvd next to it lists it, else None."""
    d = os.path.dirname(os.path.abspath(path))
    target = os.path.realpath(path)
    try:
        names = sorted(n for n in os.listdir(d) if n.endswith(".pvd"))
    except OSError:
        return None
    for n in names:
        try:
            for fr in parse_pvd(os.path.join(d, n)):
                if any(os.path.realpath(f) == target for f in fr.files):
                    return fr.time
        except InputError:
            continue
    return None


def select_frames(frames, args, pvd):
    n = len(frames)
    if args.last:
        return [frames[-1]]
    if args.frame is not None:
        k = args.frame + n if args.frame < 0 else args.frame
        if not 0 <= k < n:
            raise InputError(pvd, f"no frame {args.frame}: the series has {n} frame(s), "
                                  f"indices 0..{n - 1} (or -1..-{n})")
        return [frames[k]]
    if args.time is not None:
        timed = [f for f in frames if f.time is not None]
        if not timed:
            raise InputError(pvd, "--time given but the series has no timesteps")
        lo, hi = timed[0].time, timed[-1].time
        steps = [b.time - a.time for a, b in zip(timed, timed[1:]) if b.time > a.time]
        tol = 0.5 * max(steps) if steps else 1e-12 * max(1.0, abs(lo))
        if args.time < min(lo, hi) - tol or args.time > max(lo, hi) + tol:
            raise InputError(pvd, f"--time {args.time:g} is outside the series' times "
                                  f"{lo:g}..{hi:g}")
        return [min(timed, key=lambda f: abs(f.time - args.time))]
    return frames


# ---------------------------------------------------------------------------------------------
# Reading (VTK)


def import_vtk():
    try:
        global vtk_to_numpy, numpy_to_vtk, np, V
        import numpy as np  # noqa: F401
        from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy  # noqa: F401
        import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (registers the OpenGL back end)
        import vtkmodules.vtkRenderingFreeType  # noqa: F401  (text)
        import vtkmodules.vtkCommonCore as cc
        import vtkmodules.vtkCommonDataModel as dm
        import vtkmodules.vtkFiltersCore as fc
        import vtkmodules.vtkFiltersGeneral as fgen
        import vtkmodules.vtkFiltersGeometry as fg
        import vtkmodules.vtkIOImage as ii
        import vtkmodules.vtkIOXML as ix
        import vtkmodules.vtkRenderingAnnotation as ra
        import vtkmodules.vtkRenderingCore as rc
    except ImportError as e:
        sys.exit(f"{PROG}: cannot import VTK's Python module ({e}). It needs Debian's "
                 "python3-vtk9 and /usr/bin/python3; tools/render.sh installs it and runs this "
                 "script under xvfb-run.")

    class _V:
        pass

    V = _V()
    for mod in (cc, dm, fc, fgen, fg, ii, ix, ra, rc):
        for k in dir(mod):
            if k.startswith("vtk"):
                setattr(V, k, getattr(mod, k))
    # VTK's messages (also those of the readers a .vtm reader runs for its blocks) go to a string
    # that read_blocks() checks after each file.
    V.messages = V.vtkStringOutputWindow()
    V.vtkOutputWindow.SetInstance(V.messages)
    V.vtkLogger.SetStderrVerbosity(V.vtkLogger.VERBOSITY_OFF)


class _Errors:
    def __init__(self):
        self.messages = []

    def __call__(self, obj, event, *rest):
        self.messages.append(event)


def _reader_for(path):
    ext = os.path.splitext(path)[1].lower()
    if ext == ".vtm":
        return V.vtkXMLMultiBlockDataReader()
    if ext == ".vtu":
        return V.vtkXMLUnstructuredGridReader()
    if ext == ".vtp":
        return V.vtkXMLPolyDataReader()
    raise InputError(path, "unsupported file type (expected .pvd, .vtm, .vtu or .vtp)")


def read_blocks(path):
    """[(name, vtkDataSet)] for the leaves of a .vtm, or the one dataset of a .vtu/.vtp."""
    if not os.path.isfile(path):
        raise InputError(path, "no such file")
    reader = _reader_for(path)
    if path.lower().endswith(".vtm"):
        children = _vtm_children(path)
        if children is None:
            raise InputError(path, "not a readable .vtm (XML error)")
        for f in children:
            if not os.path.isfile(f):
                raise InputError(path, f"references {f}, which does not exist")
    errs = _Errors()
    reader.AddObserver("ErrorEvent", errs)
    V.messages = V.vtkStringOutputWindow()
    V.vtkOutputWindow.SetInstance(V.messages)
    reader.SetFileName(path)
    reader.Update()
    out = reader.GetOutputDataObject(0)
    log = V.messages.GetOutput() or ""
    if errs.messages or out is None or "ERROR" in log:
        if path.lower().endswith(".vtm"):
            for f in _vtm_children(path):
                read_blocks(f)  # names the broken block file, if one is
        detail = next((ln.strip() for ln in log.splitlines()
                       if ln.strip() and not ln.startswith(("ERROR", "Warning"))), "")
        detail = re.sub(r"^vtk\w+ \(0x[0-9a-f]+\): ", "", detail)
        raise InputError(path, "VTK could not read this file (truncated or not VTK XML?)"
                         + (f": {detail}" if detail else ""))
    blocks = []
    if out.IsA("vtkCompositeDataSet"):
        it = out.NewIterator()
        it.SkipEmptyNodesOn()
        it.InitTraversal()
        while not it.IsDoneWithTraversal():
            ds = it.GetCurrentDataObject()
            meta = it.GetCurrentMetaData() if it.HasCurrentMetaData() else None
            name = None
            if meta is not None and meta.Has(V.vtkCompositeDataSet.NAME()):
                name = meta.Get(V.vtkCompositeDataSet.NAME())
            if ds is not None and ds.IsA("vtkDataSet"):
                blocks.append((name or f"block{len(blocks)}", ds))
            it.GoToNextItem()
        if not blocks:
            raise InputError(path, "the multiblock has no datasets")
    else:
        blocks.append((os.path.splitext(os.path.basename(path))[0], out))
    return blocks


def _vtm_children(path):
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError):
        return None
    base = os.path.dirname(os.path.abspath(path))
    return [os.path.join(base, d.get("file")) for d in root.iter("DataSet") if d.get("file")]


def read_frame(frame):
    blocks = []
    for f in frame.files:
        blocks.extend(read_blocks(f))
    return blocks


# ---------------------------------------------------------------------------------------------
# Arrays


def find_array(ds, name):
    """(vtkDataArray, 'point'|'cell') or (None, None)."""
    a = ds.GetPointData().GetArray(name)
    if a is not None:
        return a, "point"
    a = ds.GetCellData().GetArray(name)
    if a is not None:
        return a, "cell"
    return None, None


def list_arrays(blocks):
    """{name: (association, components)} over all blocks, point arrays first."""
    found = {}
    for assoc in ("point", "cell"):
        for _, ds in blocks:
            data = ds.GetPointData() if assoc == "point" else ds.GetCellData()
            for i in range(data.GetNumberOfArrays()):
                a = data.GetArray(i)
                if a is not None and a.GetName() and a.GetName() not in found:
                    found[a.GetName()] = (assoc, a.GetNumberOfComponents())
    return found


def describe_arrays(found):
    if not found:
        return "(the data has no point or cell arrays)"
    return ", ".join(f"{n} ({assoc}, {c} component{'s' if c != 1 else ''})"
                     for n, (assoc, c) in found.items())


def component_index(spec, ncomp, array_name, where):
    """None for the magnitude (or the value of a 1-component array), else a component index."""
    s = spec.lower()
    if s in ("magnitude", "mag", "norm"):
        return None
    k = AXES.get(s)
    if k is None:
        try:
            k = int(s)
        except ValueError:
            raise InputError(where, f"unknown component '{spec}' "
                                    "(use magnitude, x, y, z or an index)")
    if not 0 <= k < ncomp:
        raise InputError(where, f"array '{array_name}' has {ncomp} component(s); "
                                f"component '{spec}' does not exist")
    return None if ncomp == 1 else k


def scalars(vtk_array, comp):
    a = vtk_to_numpy(vtk_array).astype(np.float64, copy=False)
    if a.ndim == 1:
        return a
    if comp is None:
        return np.sqrt(np.einsum("ij,ij->i", a, a))
    return a[:, comp]


def choose_array(args, found, where):
    if args.array is not None:
        if args.array.lower() == "none":
            return None
        if args.array not in found:
            raise InputError(where, f"no array '{args.array}'. Available: {describe_arrays(found)}")
        return args.array
    if "displacement" in found:
        return "displacement"
    return next(iter(found), None)


# ---------------------------------------------------------------------------------------------
# Scene


def colour_function(name, lo, hi):
    ctf = V.vtkColorTransferFunction()
    if name == "coolwarm":
        ctf.SetColorSpaceToDiverging()
        ctf.AddRGBPoint(lo, *COOLWARM[0])
        ctf.AddRGBPoint(hi, *COOLWARM[1])
    else:
        ctf.SetColorSpaceToRGB()
        n = len(VIRIDIS) - 1
        for i, c in enumerate(VIRIDIS):
            ctf.AddRGBPoint(lo + (hi - lo) * i / n, *c)
    ctf.SetNanColor(*NO_ARRAY_COLOUR)
    ctf.Build()
    return ctf


def clipped(ds, clip):
    """ds without the part on the dropped side of the plane clip = (axis, sign, value)."""
    axis, sign, value = clip
    plane = V.vtkPlane()
    origin = [0.0, 0.0, 0.0]
    origin[axis] = value
    normal = [0.0, 0.0, 0.0]
    normal[axis] = sign
    plane.SetOrigin(*origin)
    plane.SetNormal(*normal)
    f = V.vtkTableBasedClipDataSet()
    f.SetInputData(ds)
    f.SetClipFunction(plane)
    f.InsideOutOn()  # keep sign * (x[axis] - value) < 0
    f.Update()
    return f.GetOutput()


def surface_of(ds):
    """The outer surface with smooth normals that stay sharp across edges over 35 degrees."""
    if ds.IsA("vtkPolyData"):
        poly = ds
    else:
        sf = V.vtkDataSetSurfaceFilter()
        sf.SetInputData(ds)
        sf.Update()
        poly = sf.GetOutput()
    normals = V.vtkPolyDataNormals()
    normals.SetInputData(poly)
    normals.SetFeatureAngle(35.0)
    normals.SplittingOn()
    normals.ConsistencyOn()
    normals.AutoOrientNormalsOff()
    normals.Update()
    return normals.GetOutput()


def view_basis(view, up_axis):
    """(direction from the focal point to the camera, view-up), unit vectors."""
    e = [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
    if view == "xy":
        return e[2], e[1]
    if view == "xz":
        return (0.0, -1.0, 0.0), e[2]
    if view == "yz":
        return e[0], e[2]
    # A three-quarter view from above; the horizontal part looks along the diagonal of the two
    # other axes, tilted so that the first of them (x, or y when x is up) runs to the right.
    u = AXES[up_axis]
    d = {0: [0.85, 1.0, -1.35], 1: [1.0, 0.85, 1.35], 2: [1.0, -1.35, 0.85]}[u]
    n = math.sqrt(sum(c * c for c in d))
    return tuple(c / n for c in d), e[u]


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def set_camera(cam, bounds, view, up_axis, aspect, zoom, frac_w):
    """Fit the box `bounds` into the left `frac_w` of the picture (the scalar bar has the rest)."""
    d, up = view_basis(view, up_axis)
    right = _cross((-d[0], -d[1], -d[2]), up)
    rn = math.sqrt(_dot(right, right))
    right = tuple(c / rn for c in right)
    up = _cross(right, (-d[0], -d[1], -d[2]))
    corners = [(x, y, z) for x in bounds[0:2] for y in bounds[2:4] for z in bounds[4:6]]
    xs = [_dot(c, right) for c in corners]
    ys = [_dot(c, up) for c in corners]
    zs = [_dot(c, d) for c in corners]
    half_w = max(0.5 * (max(xs) - min(xs)), 1e-9)
    half_h = max(0.5 * (max(ys) - min(ys)), 1e-9)
    half_d = 0.5 * (max(zs) - min(zs))
    mid = (0.5 * (max(xs) + min(xs)), 0.5 * (max(ys) + min(ys)), 0.5 * (max(zs) + min(zs)))
    focal = tuple(mid[0] * right[i] + mid[1] * up[i] + mid[2] * d[i] for i in range(3))
    margin = 1.12
    scale = max(half_h, half_w / (aspect * frac_w)) * margin
    angle = 20.0
    dist = scale / math.tan(math.radians(angle / 2)) + half_d
    cam.SetViewAngle(angle)
    cam.SetFocalPoint(*focal)
    cam.SetPosition(*(focal[i] + dist * d[i] for i in range(3)))
    cam.SetViewUp(*up)
    # Put the focal point in the middle of the free part of the picture, not of the whole.
    cam.SetWindowCenter(1.0 - frac_w, 0.0)
    cam.Zoom(zoom)
    cam.SetClippingRange(max(dist - 4 * half_d - scale, dist * 1e-3), dist + 4 * half_d + scale)


def text_width(tprop, text):
    """The width in pixels of `text` drawn with `tprop`."""
    bbox = [0, 0, 0, 0]
    try:
        if V.vtkTextRenderer.GetInstance().GetBoundingBox(tprop, text, bbox, 72):
            return bbox[1] - bbox[0] + 1
    except (AttributeError, TypeError):
        pass
    return 0.62 * tprop.GetFontSize() * len(text)


class Scene:
    def __init__(self, args, array, comp, assoc, lo, hi, cmap, title, time_fmt):
        self.args, self.array, self.comp, self.assoc = args, array, comp, assoc
        self.clip = None
        w, h = args.size
        self.ren = V.vtkRenderer()
        self.ren.GradientBackgroundOn()
        self.ren.SetBackground(*BG_BOTTOM)
        self.ren.SetBackground2(*BG_TOP)
        self.ren.UseFXAAOn()
        self.ren.AutomaticLightCreationOff()
        kit = V.vtkLightKit()
        kit.SetKeyLightIntensity(0.8)
        kit.SetKeyToFillRatio(1.8)
        kit.SetKeyToHeadRatio(2.5)
        kit.AddLightsToRenderer(self.ren)
        self.win = V.vtkRenderWindow()
        self.win.SetOffScreenRendering(1)
        self.win.SetSize(w, h)
        self.win.AddRenderer(self.ren)
        self.win.SetMultiSamples(0)
        translucent = args.opacity_all < 1.0 or any(v < 1.0 for v in args.opacity_of.values())
        if array and args.fade is not None and args.fade < 1.0:
            translucent = True
        if translucent:
            # Order-independent translucency, so bodies inside translucent ones show correctly.
            self.win.SetAlphaBitPlanes(1)
            self.ren.SetUseDepthPeeling(1)
            self.ren.SetMaximumNumberOfPeels(12)
            self.ren.SetOcclusionRatio(0.0)
        self.ctf = colour_function(cmap, lo, hi) if array else None
        self.lut = self.ctf
        if array and args.fade is not None:
            # The colour map with an opacity ramp: `fade` at the bottom, opaque from 4 % up.
            n = 256
            self.lut = V.vtkLookupTable()
            self.lut.SetNumberOfTableValues(n)
            self.lut.SetTableRange(lo, hi)
            for i in range(n):
                x = i / (n - 1)
                c = self.ctf.GetColor(lo + x * (hi - lo))
                mix = min(1.0, x / 0.04)  # 0: a grey ghost; 1: the colour map, opaque
                r, g, b = (mix * c[k] + (1.0 - mix) * NO_ARRAY_COLOUR[k] for k in range(3))
                self.lut.SetTableValue(i, r, g, b, args.fade + (1.0 - args.fade) * mix)
            self.lut.SetNanColor(*NO_ARRAY_COLOUR, args.fade)
            self.lut.SetScaleToLinear()
        self.lo, self.hi = lo, hi
        self.actors = []
        self.time_fmt = time_fmt
        fs = max(12, int(round(h / 40)))
        self.title = V.vtkTextActor()
        self.title.SetInput(title)
        self._style(self.title.GetTextProperty(), fs, bold=True)
        self.title.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
        self.title.GetPositionCoordinate().SetValue(0.02, 1.0 - (0.02 * h + fs) / h)
        self.ren.AddActor2D(self.title)
        self.clock = V.vtkTextActor()
        self._style(self.clock.GetTextProperty(), fs)
        self.clock.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
        self.clock.GetPositionCoordinate().SetValue(0.02, 1.0 - (0.02 * h + 2.3 * fs) / h)
        self.ren.AddActor2D(self.clock)
        self.bar_frac = 0.0
        if array:
            bar = V.vtkScalarBarActor()
            bar.SetLookupTable(self.ctf)
            label = array
            if comp is not None:
                label += f" [{'xyz'[comp] if comp < 3 else comp}]"
            elif self.args.ncomp > 1:
                label = f"|{array}|"
            bar.SetTitle(label)
            ticks = V.vtkDoubleArray()
            for i in range(5):
                v = lo + (hi - lo) * i / 4
                ticks.InsertNextValue(0.0 if abs(v) < 1e-9 * (hi - lo) else v)
            bar.SetUseCustomLabels(True)
            bar.SetCustomLabels(ticks)
            bar.SetNumberOfLabels(5)
            bar.SetLabelFormat(label_format(lo, hi, 5))
            bar.SetTextPad(max(4, fs // 3))
            bar.SetMaximumNumberOfColors(256)
            bar.SetTextPositionToSucceedScalarBar()
            bar.SetBarRatio(0.28)
            bar.SetTitleRatio(0.6)
            bar.UnconstrainedFontSizeOn()
            bar.DrawTickLabelsOn()
            bar.SetVerticalTitleSeparation(int(0.6 * fs))
            self._style(bar.GetTitleTextProperty(), int(fs * 1.0), bold=True)
            self._style(bar.GetLabelTextProperty(), int(fs * 0.9))
            # Wide enough for its title (centred over bar and labels), at the right edge.
            title_w = text_width(bar.GetTitleTextProperty(), label) + 0.5 * fs
            width = min(0.45, max(0.13, title_w / w))
            bar.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
            bar.SetPosition(0.99 - width, 0.12)
            bar.SetWidth(width)
            bar.SetHeight(0.74)
            self.ren.AddActor2D(bar)
            self.bar_frac = width + 0.03
        self.to_image = V.vtkWindowToImageFilter()
        self.to_image.SetInput(self.win)
        self.to_image.SetInputBufferTypeToRGB()
        self.to_image.ReadFrontBufferOff()
        self.writer = V.vtkPNGWriter()
        self.writer.SetInputConnection(self.to_image.GetOutputPort())

    @staticmethod
    def _style(tp, size, bold=False):
        tp.SetFontFamilyToArial()
        tp.SetFontSize(size)
        tp.SetColor(*TEXT_COLOUR)
        tp.SetBold(bool(bold))
        tp.SetItalic(False)
        tp.SetShadow(False)

    def set_camera(self, bounds):
        w, h = self.args.size
        set_camera(self.ren.GetActiveCamera(), bounds, self.args.view, self.args.up, w / h,
                   self.args.zoom, 1.0 - self.bar_frac)

    def show(self, blocks, time):
        for a in self.actors:
            self.ren.RemoveActor(a)
        self.actors = []
        for name, ds in blocks:
            opacity = self.args.opacity_of.get(name, self.args.opacity_all)
            if opacity <= 0.0:
                continue
            if self.clip is not None:
                ds = clipped(ds, self.clip)
                if ds.GetNumberOfCells() == 0:
                    continue
            poly = surface_of(ds)
            mapper = V.vtkPolyDataMapper()
            mapper.SetInputData(poly)
            arr, assoc = (find_array(poly, self.array) if self.array else (None, None))
            if arr is not None:
                vals = scalars(arr, self.comp)
                s = numpy_to_vtk(np.ascontiguousarray(vals), deep=1)
                s.SetName("render_scalar")
                data = poly.GetPointData() if assoc == "point" else poly.GetCellData()
                data.AddArray(s)
                mapper.SetLookupTable(self.lut)
                mapper.UseLookupTableScalarRangeOn()
                mapper.SetScalarVisibility(1)
                mapper.SetColorModeToMapScalars()
                if assoc == "point":
                    mapper.SetScalarModeToUsePointFieldData()
                    mapper.InterpolateScalarsBeforeMappingOn()
                else:
                    mapper.SetScalarModeToUseCellFieldData()
                mapper.SelectColorArray("render_scalar")
            else:
                mapper.ScalarVisibilityOff()
            actor = V.vtkActor()
            actor.SetMapper(mapper)
            prop = actor.GetProperty()
            prop.SetInterpolationToPhong()
            prop.SetColor(*NO_ARRAY_COLOUR)
            prop.SetAmbient(0.18)
            prop.SetDiffuse(0.85)
            prop.SetSpecular(0.18)
            prop.SetSpecularPower(28.0)
            if opacity < 1.0:
                prop.SetOpacity(opacity)
            if self.args.edges:
                prop.EdgeVisibilityOn()
                prop.SetEdgeColor(0.15, 0.15, 0.17)
                prop.SetLineWidth(1.0)
            self.ren.AddActor(actor)
            self.actors.append(actor)
        self.clock.SetInput("" if time is None else "t = " + (self.time_fmt % time) + " s")

    def write(self, path):
        self.win.Render()
        self.to_image.Modified()
        self.writer.SetFileName(path)
        self.writer.Write()
        if not os.path.isfile(path) or os.path.getsize(path) == 0:
            raise RuntimeError(f"{path}: writing the PNG failed")


def label_format(lo, hi, labels):
    """Fixed point with enough decimals to tell the scalar bar's labels apart, else %.3g."""
    big = max(abs(lo), abs(hi))
    step = (hi - lo) / max(1, labels - 1)
    if big >= 1e6 or big < 1e-3 or step <= 0:
        return "%-#.3g"
    decimals = max(0, 2 - int(math.floor(math.log10(step))))
    return f"%.{min(decimals, 6)}f"


def time_format(times):
    """A fixed-point format with as few decimals as shows every time of the series exactly."""
    ts = sorted({t for t in times if t is not None})
    if not ts:
        return "%g"
    scale = max(abs(ts[0]), abs(ts[-1]))
    if scale >= 1e5 or 0 < scale < 1e-4:
        return "%.4e"
    for decimals in range(0, 7):
        if all(abs(t * 10 ** decimals - round(t * 10 ** decimals)) < 1e-6 for t in ts):
            return f"%.{max(decimals, 1 if len(ts) > 1 else 0)}f"
    return "%.6f"


def union_bounds(b, ds_bounds):
    if b is None:
        return list(ds_bounds)
    return [min(b[0], ds_bounds[0]), max(b[1], ds_bounds[1]), min(b[2], ds_bounds[2]),
            max(b[3], ds_bounds[3]), min(b[4], ds_bounds[4]), max(b[5], ds_bounds[5])]


def filter_blocks(blocks, wanted, where):
    if not wanted:
        return blocks
    names = [n for n, _ in blocks]
    for w in wanted:
        if w not in names:
            raise InputError(where, f"no block '{w}'. Blocks: {', '.join(names)}")
    return [(n, ds) for n, ds in blocks if n in wanted]


# ---------------------------------------------------------------------------------------------
# Animation


def make_animation(png_dir, stem, names, fps):
    """NAME.mp4 with ffmpeg, else an animated GIF with Pillow, else a note. Returns a message.
    `names`: the PNGs in png_dir, in order (numbered by step, so not consecutive)."""
    ffmpeg = shutil.which("ffmpeg")
    if ffmpeg:
        out = os.path.join(png_dir, stem + ".mp4")
        # ffmpeg reads an image sequence by consecutive numbers: link the PNGs as 0, 1, 2, ...
        with tempfile.TemporaryDirectory(prefix="render_") as seq:
            for i, name in enumerate(names):
                os.symlink(os.path.abspath(os.path.join(png_dir, name)), os.path.join(seq, f"{i:06d}.png"))
            cmd = [ffmpeg, "-y", "-loglevel", "error", "-framerate", f"{fps:g}",
                   "-i", os.path.join(seq, "%06d.png"), "-frames:v", str(len(names)),
                   "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2,format=yuv420p",
                   "-c:v", "libx264", "-crf", "20", "-movflags", "+faststart", out]
            r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0 or not os.path.isfile(out):
            raise RuntimeError(f"{out}: ffmpeg failed: {r.stderr.strip() or r.returncode}")
        return f"wrote {out}"
    try:
        from PIL import Image
    except ImportError:
        return ("no animation: neither ffmpeg nor Pillow is installed "
                "(tools/render.sh --with-ffmpeg installs ffmpeg)")
    out = os.path.join(png_dir, stem + ".gif")
    images = [Image.open(os.path.join(png_dir, name)).convert("RGB") for name in names]
    pal = [im.quantize(colors=255, method=Image.Quantize.MEDIANCUT) for im in images]
    pal[0].save(out, save_all=True, append_images=pal[1:], duration=int(round(1000 / fps)),
                loop=0, optimize=True)
    return f"wrote {out} (ffmpeg not installed: animated GIF instead of {stem}.mp4)"


# ---------------------------------------------------------------------------------------------


def run(args):
    src = args.input
    if not os.path.exists(src):
        raise InputError(src, "no such file")
    ext = os.path.splitext(src)[1].lower()
    if ext == ".pvd":
        series = parse_pvd(src)
        for fr in series:
            for f in fr.files:
                if not os.path.isfile(f):
                    raise InputError(src, f"lists {f}, which does not exist")
        chosen = select_frames(series, args, src)
        stem = os.path.splitext(os.path.basename(src))[0]
    else:
        if args.frame not in (None, 0, -1) or args.time is not None:
            raise InputError(src, "--frame/--time need a .pvd series; this is a single file")
        _reader_for(src)  # unsupported extension -> InputError
        series = [Frame(0, time_from_sibling_pvd(src), [os.path.abspath(src)])]
        chosen = series
        stem = os.path.splitext(os.path.basename(src))[0]
    explicit = ext != ".pvd" or args.frame is not None or args.time is not None or args.last
    single = explicit or (len(series) == 1 and
                          (args.out is None or args.out.lower().endswith(".png")))
    wanted = [b.strip() for b in args.blocks.split(",") if b.strip()] if args.blocks else None

    # Pass 1: arrays and colour range over the series, bounds over what the camera fits.
    fit = args.fit or ("frame" if single else "series")
    found = {}
    first = read_frame(chosen[0])
    filter_blocks(first, wanted, chosen[0].files[0])
    filter_blocks(first, list(args.opacity_of), chosen[0].files[0])  # unknown names -> error
    found.update(list_arrays(first))
    array = choose_array(args, found, src)
    comp, assoc, ncomp = None, None, 1
    if array:
        assoc, ncomp = found[array]
        comp = component_index(args.component, ncomp, array, src)
    args.ncomp = ncomp
    lo, hi, bounds = math.inf, -math.inf, None
    need_range = array is not None and args.range is None
    for fr in series:
        in_fit = fit == "series" or fr in chosen
        if not (in_fit or need_range):
            continue
        blocks = first if fr is chosen[0] else read_frame(fr)
        blocks = filter_blocks(blocks, wanted, fr.files[0])
        for _, ds in blocks:
            if in_fit and ds.GetNumberOfPoints() > 0:
                bounds = union_bounds(bounds, ds.GetBounds())
            if need_range:
                a, _ = find_array(ds, array)
                if a is not None and a.GetNumberOfTuples() > 0:
                    v = scalars(a, comp)
                    v = v[np.isfinite(v)]
                    if v.size:
                        lo, hi = min(lo, float(v.min())), max(hi, float(v.max()))
    if bounds is None:
        raise InputError(chosen[0].files[0], "nothing to draw: every block is empty")
    if args.range is not None:
        lo, hi = args.range
    elif not lo <= hi:
        lo, hi = 0.0, 1.0
    elif hi - lo <= 1e-12 * max(1.0, abs(lo), abs(hi)):
        # A constant array: a range around the value that does not cross zero.
        lo, hi = (0.0, 1.0) if lo == 0 else (lo - 0.5 * abs(lo), hi + 0.5 * abs(hi))
    cmap = args.cmap
    if cmap == "auto":
        cmap = "coolwarm" if (lo < 0 < hi and array) else "viridis"
    if cmap == "coolwarm" and args.range is None and lo < 0 < hi:
        lo, hi = -max(-lo, hi), max(-lo, hi)  # white at zero

    title = args.title if args.title is not None else stem
    scene = Scene(args, array, comp, assoc, lo, hi, cmap, title,
                  time_format([f.time for f in series]))
    scene.set_camera(bounds)
    if args.clip_spec is not None:
        axis, sign, value = args.clip_spec
        if value is None:
            value = 0.5 * (bounds[2 * axis] + bounds[2 * axis + 1])
        scene.clip = (axis, sign, value)
    if array:
        how = "" if ncomp == 1 else (", magnitude" if comp is None else f", component {comp}")
        what = f"array {array} ({assoc}{how}), range {lo:.4g}..{hi:.4g}"
    else:
        what = "no array"

    if single:
        fr = chosen[0]
        out = args.out
        if out is None:
            base = os.path.splitext(os.path.abspath(src))[0]
            out = base + (f"_{fr.number():06d}" if ext == ".pvd" else "") + ".png"
        elif os.path.isdir(out):
            out = os.path.join(out, f"{stem}_{fr.number():06d}.png")
        if not out.lower().endswith(".png"):
            raise InputError(out, "--out for one frame must be a .png file (or a directory)")
        parent = os.path.dirname(os.path.abspath(out))
        if not os.path.isdir(parent):
            raise InputError(out, f"directory {parent} does not exist")
        blocks = first if fr is chosen[0] else read_frame(fr)
        scene.show(filter_blocks(blocks, wanted, fr.files[0]), fr.time)
        scene.write(out)
        tinfo = "" if fr.time is None else f", t = {fr.time:g}"
        print(f"{PROG}: wrote {out} (frame {fr.index}{tinfo}; {what})")
        return 0

    out_dir = args.out or os.path.join(os.path.dirname(os.path.abspath(src)), stem + "_render")
    if out_dir.lower().endswith(".png"):
        raise InputError(out_dir, "a series renders into a directory; use --frame K, --time T or "
                                  "--last for one PNG")
    try:
        os.makedirs(out_dir, exist_ok=True)
    except OSError as e:
        raise InputError(out_dir, f"cannot create the output directory: {e.strerror}")
    names = [f"{stem}_{fr.number():06d}.png" for fr in chosen]
    if len(set(names)) != len(names):  # not corocontact's naming: number by position instead
        names = [f"{stem}_{i:06d}.png" for i in range(len(chosen))]
    for name, fr in zip(names, chosen):
        blocks = filter_blocks(first if fr is chosen[0] else read_frame(fr), wanted, fr.files[0])
        if fit == "frame":  # the camera follows the bodies
            fb = None
            for _, ds in blocks:
                if ds.GetNumberOfPoints() > 0:
                    fb = union_bounds(fb, ds.GetBounds())
            scene.set_camera(fb or bounds)
        scene.show(blocks, fr.time)
        scene.write(os.path.join(out_dir, name))
    print(f"{PROG}: wrote {len(chosen)} PNGs to {out_dir}/{stem}_<step>.png, numbered like the "
          f"series' frames ({what})")
    if args.no_animation:
        return 0
    if len(chosen) < 2:
        print(f"{PROG}: no animation: the series has a single frame")
        return 0
    print(f"{PROG}: {make_animation(out_dir, stem, names, args.fps)}")
    return 0


def maybe_reexec_under_xvfb(argv):
    """Without an X display, run again under xvfb-run (which VTK's X/GLX window needs)."""
    if os.environ.get("DISPLAY") or os.environ.get("CORO_RENDER_NO_XVFB"):
        return
    xvfb = shutil.which("xvfb-run")
    if not xvfb:
        sys.exit(f"{PROG}: no X display (DISPLAY is unset) and xvfb-run is not installed; "
                 "run tools/render.sh, which installs xvfb and uses it")
    env = dict(os.environ, CORO_RENDER_NO_XVFB="1")
    cmd = [xvfb, "-a", "-s", "-screen 0 1920x1080x24 -nolisten tcp",
           sys.executable, os.path.abspath(__file__)] + argv
    os.execve(xvfb, cmd, env)


def main(argv):
    try:
        args = parse_args(argv)
    except InputError as e:
        print(f"{PROG}: {e}", file=sys.stderr)
        return 2
    maybe_reexec_under_xvfb(argv)
    import_vtk()
    try:
        return run(args)
    except InputError as e:
        print(f"{PROG}: {e}", file=sys.stderr)
        return 2
    except RuntimeError as e:
        print(f"{PROG}: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
