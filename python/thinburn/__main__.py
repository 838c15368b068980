"""Command line: `python -m thinburn demo|wedge|usd|bake [options]`."""
from __future__ import annotations

import argparse
import os
import sys


def _parser() -> argparse.ArgumentParser:
    from .materials import MATERIALS

    p = argparse.ArgumentParser(prog="python -m thinburn", description="Burn thin shells.")
    sub = p.add_subparsers(dest="command", required=True)
    d = sub.add_parser("demo", help="burn a built-in scene: an A4 sheet on a table lit at a corner "
                                    "(paper, hard_paper), a cloth held at its corners (cloth, silk), "
                                    "a curtain in wind (curtain); --scene lantern|sphere|letter "
                                    "burns a curved shell instead")
    d.add_argument("--material", default="paper", choices=sorted(MATERIALS))
    d.add_argument("--scene", default=None, choices=["lantern", "sphere", "letter"],
                   help="a curved shell instead of the material's own scene: a paper lantern "
                        "(open cylinder r = 10 cm, h = 30 cm) on a table lit on its side, a sphere "
                        "(r = 10 cm) on a table lit on its equator, or an A4 sheet folded at 30 "
                        "degrees on a table; burnt with --material (default paper)")
    d.add_argument("--cells", type=int, default=128, help="N: cells per side (default 128)")
    d.add_argument("--fps", type=float, default=24.0, help="simulation steps per second")
    d.add_argument("--frames", type=int, default=60, help="pictures to write (default 60)")
    d.add_argument("--max-time", type=float, default=240.0, help="stop after this many seconds")
    d.add_argument("--seed", type=int, default=0)
    d.add_argument("--threads", type=int, default=None)
    d.add_argument("--out", default=None, help="output folder (default thinburn_out/demo_MATERIAL)")
    d.add_argument("--quiet", action="store_true", help="no progress bar")
    from ._farm_cli import add_farm_commands
    add_farm_commands(sub)
    return p


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "demo":
        from .demo import run_demo

        if args.cells < 8 or args.cells > 2048:
            print("error: --cells must be between 8 and 2048", file=sys.stderr)
            return 2
        if args.frames < 1 or args.fps <= 0 or args.max_time <= 0:
            print("error: --frames, --fps and --max-time must be positive", file=sys.stderr)
            return 2
        if args.scene is None:
            name = f"demo_{args.material}"
        else:
            name = f"demo_{args.scene}" + ("" if args.material == "paper" else f"_{args.material}")
        out = args.out or os.path.join("thinburn_out", name)
        print(f"thinburn demo: writing to {os.path.abspath(out)}", file=sys.stderr)
        s = run_demo(out, args.material, args.cells, args.fps, args.max_time, args.frames,
                     args.seed, args.threads, args.quiet, scene=args.scene)
        print(f"done: {s['simulated_seconds']} s simulated in {s['wall_seconds']} s "
              f"({s['simulated_frames_per_second']} simulated frames/s, drawing excluded); "
              f"{s['frames_written']} frames, "
              f"{100 * s['burnt_fraction']:.1f} % burnt -> {os.path.abspath(out)}")
        return 0
    from ._farm_cli import run_farm_command
    return run_farm_command(args)


if __name__ == "__main__":
    sys.exit(main())
