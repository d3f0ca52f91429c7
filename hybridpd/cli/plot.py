"""``hybridpd plot``: draw a result file that hybridpd wrote."""
from __future__ import annotations

from pathlib import Path

from hybridpd.cli._common import IMAGE_SUFFIXES, check_image, command, write_figure

DESCRIPTION = ("Draws a result file written by hybridpd to an image: a region map "
               "(existence and stability over the gains, Figs 4-5), a basin of "
               "attraction (Figs 6-7), a brute-force bifurcation diagram, a continued "
               "branch, or a trajectory written by 'simulate --out FILE.json'. The kind "
               "is read from the file's own metadata, not from its name.")


def register(sub):
    p = command(sub, "plot", help="draw a result file (regions, basin, diagram, branch, "
                                  "trajectory) to PNG/PDF/SVG",
                description=DESCRIPTION,
                example=("hybridpd plot regions.nc --out regions.pdf\n  hybridpd plot "
                         "run.json   # writes run.png"))
    p.add_argument("file", metavar="FILE",
                   help="result file (.nc, .zarr, .npz or .json written by hybridpd)")
    p.add_argument("--out", default=None, metavar="IMAGE",
                   help="image to write, " + ", ".join(IMAGE_SUFFIXES)
                        + " (default: FILE with its suffix replaced by .png)")
    p.add_argument("--title", default=None, help="title replacing the default one")
    p.add_argument("--coordinate", default=None,
                   choices=["phi", "z1", "z2", "z4", "x1", "y1", "x2", "y2"],
                   help="bifurcation diagrams: section coordinate on the y axis "
                        "(default z1)")
    p.add_argument("--quantity", default=None,
                   choices=["spectral_radius", "margin", "xm", "min_impact_speed",
                            "multipliers", "0", "1", "2", "3"],
                   help="branches: quantity against the parameter (0-3: coordinate of the "
                        "fixed point phi, z1, z2, z4; default spectral_radius)")
    p.set_defaults(func=run)


def default_image(path) -> Path:
    """FILE with its suffix replaced by ``.png`` (a ``.zarr`` store's name included)."""
    return Path(str(path).rstrip("/\\")).with_suffix(".png")


def run(args) -> int:
    # deferred import: loaded only when this runs, for start-up time
    from hybridpd.plotting.files import plot_file

    out = check_image(args.out, "--out") if args.out else default_image(args.file)
    if Path(out).resolve() == Path(args.file).resolve():
        raise ValueError(f"--out {str(out)!r} would overwrite FILE; give another --out")
    quantity = args.quantity
    if quantity is not None and quantity.isdigit():
        quantity = int(quantity)
    fig = plot_file(args.file, title=args.title, coordinate=args.coordinate,
                    quantity=quantity)
    write_figure(fig, out)
    print(f"wrote {out}")
    return 0
