"""The farm commands of ``python -m thinburn``: ``wedge``, ``usd`` and ``bake`` (docs/farm.md)."""
from __future__ import annotations

import os
import sys


def add_farm_commands(sub) -> None:
    from .materials import MATERIALS

    w = sub.add_parser("wedge", help="bake a scene once per combination of parameter values, as "
                                     "Dask tasks, with a contact sheet")
    w.add_argument("--scene", default="paper",
                   help=f"a demo scene ({', '.join(sorted(MATERIALS))}) or a scene file (.json, .npz)")
    w.add_argument("--param", action="append", default=[], metavar="NAME=V1,V2,...",
                   help="a parameter and its values; repeat for more (every combination is baked)")
    w.add_argument("--out", default=None, help="output folder (default thinburn_out/wedge_SCENE)")
    w.add_argument("--frames", type=int, default=None, help="frames to bake (demo default 240)")
    w.add_argument("--fps", type=float, default=None, help="frames per second (demo default 24)")
    w.add_argument("--cells", type=int, default=None, help="cells per side (demo default 64)")
    w.add_argument("--vertices", type=int, default=None,
                   help="demo scenes: remesh the sheet to about this many vertices")
    w.add_argument("--seed", type=int, default=None)
    w.add_argument("--render-frames", default=None, metavar="K1,K2,...",
                   help="frame indices (0-based) in each wedge's picture and the contact sheet "
                        "(default 4 evenly spaced, the last included)")
    w.add_argument("--workers", type=int, default=2,
                   help="LocalCluster worker processes (default 2; 0: a plain loop, no Dask)")
    w.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="a Dask scheduler's address (tcp://host:8786) instead of a LocalCluster")
    w.add_argument("--usd", action="store_true", help="also write bake.usda in each wedge folder")

    u = sub.add_parser("usd", help="export a demo's or a wedge's frames.npz to USD")
    u.add_argument("frames", help="frames.npz, or the folder that holds it")
    u.add_argument("--out", default=None, help="the .usda / .usdc file (default bake.usda beside it)")
    u.add_argument("--fps", type=float, default=None, help="default: summary.json's")

    b = sub.add_parser("bake", help="bake a .blend's ThinBurn sheets without the UI (needs bpy and "
                                    "the add-on)")
    b.add_argument("blend", help="the .blend file")
    b.add_argument("--object", action="append", default=None, metavar="NAME",
                   help="bake this sheet (repeat for more; default: every enabled sheet in the scene)")
    b.add_argument("--no-save", action="store_true", help="do not save the .blend after the bake")
    b.add_argument("--usd", default=None, metavar="FOLDER",
                   help="also export each baked sheet to FOLDER/<name>.usda")
    b.add_argument("--addon", default=None, metavar="MODULE",
                   help="the add-on's module (default: the enabled or installed ThinBurn add-on: "
                        "bl_ext.<repo>.thinburn or thinburn_addon)")


def run_farm_command(args) -> int:
    if args.command == "wedge":
        return _wedge(args)
    if args.command == "usd":
        return _usd(args)
    if args.command == "bake":
        return _bake(args)
    raise SystemExit(f"unknown command {args.command!r}")


def _err(text: str) -> int:
    print(f"error: {text}", file=sys.stderr)
    return 2


def _log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def _wedge(args) -> int:
    from . import wedge
    from .materials import MATERIALS
    from .scenefile import demo_scene, load_scene

    try:
        params = [wedge.parse_param(p) for p in args.param]
        wedge.combinations(params)
        if args.scene in MATERIALS:
            spec = demo_scene(args.scene, cells=args.cells or 64, fps=args.fps or 24.0,
                              frames=args.frames or 240, vertices=args.vertices,
                              seed=args.seed or 0)
        elif os.path.exists(args.scene):
            spec = load_scene(args.scene)
            for key in ("cells", "fps", "frames", "seed"):
                if getattr(args, key) is not None:
                    setattr(spec, key, getattr(args, key))
        else:
            return _err(f"--scene {args.scene!r}: neither a demo scene ({', '.join(sorted(MATERIALS))}) "
                        "nor an existing scene file")
        if spec.frames < 1 or spec.fps <= 0 or spec.cells < 2:
            return _err("--frames, --fps and --cells must be positive (cells >= 2)")
        render_frames = None
        if args.render_frames:
            try:
                render_frames = [int(x) for x in args.render_frames.split(",")]
            except ValueError:
                return _err(f"--render-frames {args.render_frames!r}: write frame indices like 0,12,23")
        if args.workers < 0:
            return _err(f"--workers must be >= 0, got {args.workers}")
    except (ValueError, TypeError) as exc:
        return _err(str(exc))
    out = args.out or os.path.join("thinburn_out", "wedge_" + os.path.splitext(os.path.basename(args.scene))[0])
    n = len(wedge.combinations(params))
    _log(f"thinburn wedge: {n} wedge(s) of '{spec.name}' ({spec.frames} frames at {spec.fps:g} fps, "
         f"{spec.cells} cells) -> {os.path.abspath(out)}")
    res = wedge.run_wedges(spec, params, out, render_frames=render_frames, workers=args.workers,
                           scheduler=args.scheduler, usd=args.usd, log=_log)
    _log(f"done: {len(res['done'])} baked, {len(res['skipped'])} skipped (done before), "
         f"{len(res['failed'])} failed in {res['wall_seconds']:.1f} s; contact sheet: "
         f"{res['contact_sheet'] or 'none (no wedge finished)'}")
    for name, text in res["failed"].items():
        _log(f"failed: {name}: {text}")
    return 1 if res["failed"] else 0


def _usd(args) -> int:
    from .usd import export_frames

    src = args.frames
    if os.path.isdir(src):
        src = os.path.join(src, "frames.npz")
    if not os.path.exists(src):
        return _err(f"frames: {src!r} does not exist")
    out = args.out or os.path.join(os.path.dirname(os.path.abspath(src)), "bake.usda")
    try:
        export_frames(src, out, fps=args.fps)
    except (ValueError, TypeError, ImportError) as exc:
        return _err(str(exc))
    _log(f"wrote {os.path.abspath(out)}")
    return 0


def _bake(args) -> int:
    try:
        import bpy  # noqa: F401  (Blender as a Python module)
    except ImportError as exc:
        return _err(f"bake needs Blender's Python module bpy (pip install bpy on CPython 3.11), "
                    f"or run it inside Blender: blender -b FILE --python-expr \"import "
                    f"thinburn_addon.headless as h; h.main()\" -- ... ({exc})")
    if not os.path.exists(args.blend):
        return _err(f"blend: {args.blend!r} does not exist")
    try:
        headless = find_addon(args.addon)
    except ImportError as exc:
        return _err(str(exc))
    return headless.bake_file(os.path.abspath(args.blend), objects=args.object,
                              save=not args.no_save, usd=args.usd)


def find_addon(name=None):
    """The add-on's ``headless`` module, enabled: ``name``, or the installed ThinBurn add-on."""
    import importlib

    import addon_utils

    candidates = [name] if name else []
    if not name:
        for mod in addon_utils.modules(refresh=True):
            info = getattr(mod, "bl_info", {}) or {}
            if info.get("name") == "ThinBurn" or mod.__name__.split(".")[-1] in ("thinburn_addon",):
                candidates.append(mod.__name__)
    tried = []
    for cand in candidates:
        try:
            addon_utils.enable(cand, default_set=False, handle_error=_raise)
            return importlib.import_module(f"{cand}.headless")
        except Exception as exc:  # try the next one, report them all
            tried.append(f"{cand}: {type(exc).__name__}: {exc}")
    raise ImportError("the ThinBurn add-on was not found: install it (docs/blender.md) or pass "
                      "--addon MODULE" + ("; tried " + "; ".join(tried) if tried else ""))


def _raise(exc):
    raise exc
