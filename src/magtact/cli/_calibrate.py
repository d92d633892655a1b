"""`magtact calibrate`: the sensor's field-to-force map for firmware, and a built unit's
calibration from presses (docs/method.md §13)."""

from __future__ import annotations

import sys
from functools import cache
from pathlib import Path
from typing import Annotated

import typer

from .._errors import MagtactError
from ..study import from_si
from ._app import OutOpt, StudyArg, app, console, get_study, outputs
from ._budget import (
    GOpt,
    GradeOpt,
    HOpt,
    SettingOpt,
    SiliconeOpt,
    StandoffOpt,
    check_sensor_options,
    chosen_or_given,
    noise_override,
    parse_noise,
    print_sensor_line,
)
from ._optimise import ModelsOpt


def fit_names(text: str, presses: bool) -> tuple[str, ...]:
    """The unit parameters of ``--fit`` (comma-separated names of
    :data:`magtact.calibration.PARAMETERS`).

    Raises
    ------
    MagtactError
        If there is nothing to fit the parameters to (no ``--presses``), if no name is given,
        or a name is unknown or given twice; the message says why.
    """
    from ..calibration import PARAMETERS

    if not presses:
        raise MagtactError("--fit cannot take effect without --presses: the unit's parameters "
                           "are fitted to a built unit's presses; give --presses CSV, or leave "
                           "--fit out")
    names = [p.strip() for p in text.split(",")]
    if not any(names):
        raise MagtactError(f"--fit names no parameter ({text!r}): give one or more of "
                           f"{', '.join(PARAMETERS)}, or leave --fit out for the default")
    for name in names:
        if name not in PARAMETERS:
            what = "an empty name between commas" if not name else f"unknown {name!r}"
            raise MagtactError(f"--fit: {what}; the parameters are {', '.join(PARAMETERS)}")
    if len(set(names)) != len(names):
        twice = next(n for n in names if names.count(n) > 1)
        raise MagtactError(f"--fit names {twice!r} twice")
    return tuple(names)


@cache
def freeze_at_exit() -> None:
    """Have the interpreter's exit leave the objects alive then to the process's end.

    Its last garbage collection would walk every object of the libraries the command imported
    (SymPy's, xarray's, SciPy's: a second of the command's time on a loaded machine) to free
    memory that the system takes back at once; :func:`gc.freeze` at exit (an :mod:`atexit`
    handler, registered once) moves them out of its reach. Objects are still freed as their
    references go, and what is made after the handler is collected as before.
    """
    import atexit
    import gc

    atexit.register(gc.freeze)


def _draw_figures(conn, parent_end) -> None:
    """The figure process of :class:`FigureProcess`: import the figures' code, then draw the
    calibration it is sent and answer ``("ok", "")`` or ``("error", "what failed")``."""
    import pickle
    import signal
    import warnings

    parent_end.close()  # the command's end: closed here, its exit ends recv() below
    # Ctrl-C is the command's to handle, and the handlers the command's process set for SIGTERM
    # are not this process's: it ends when the command ends it
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    warnings.simplefilter("ignore")  # nothing of this process reaches the terminal
    try:
        from ..report import calibration_figures

        data, folder = conn.recv()
    except Exception:  # the command ended before its calibration, or draws the figure itself
        return
    try:
        calibration_figures(pickle.loads(data), folder)
    except Exception as exc:
        conn.send(("error", f"{type(exc).__name__}: {exc}"))
    else:
        conn.send(("ok", ""))


class FigureProcess:
    """The calibration figure drawn by a second process.

    Started before the design, the process imports matplotlib and the figures' code while the
    design and the calibration are computed (the command's own process never imports them);
    :meth:`draw` hands it the calibration, drawn while the command writes its other files, and
    :meth:`wait` returns when ``calibration.png`` and ``.svg`` are written. Where no process
    starts by fork (systems other than Linux), the calibration does not pickle or the process
    has died, :meth:`wait` draws the figure in the command's process.
    """

    def __init__(self):
        self._job = None  # (calibration, folder) until its figure is written
        self._sent = False
        self._proc = self._conn = None
        if sys.platform.startswith("linux"):
            import multiprocessing

            ctx = multiprocessing.get_context("fork")
            self._conn, child = ctx.Pipe()
            self._proc = ctx.Process(target=_draw_figures, args=(child, self._conn),
                                     daemon=True)
            self._proc.start()
            child.close()

    def draw(self, cal, folder: Path) -> None:
        """Hand the calibration's figure (written in ``folder``) to the process."""
        import pickle

        self._job = (cal, folder)
        if self._proc is not None:
            try:
                self._conn.send((pickle.dumps(cal), folder))
                self._sent = True
            except Exception:  # a calibration that does not pickle, a process gone
                pass

    def wait(self) -> None:
        """Return when the figure's files are written.

        Raises
        ------
        RuntimeError
            If the process could not write the figure (the message says why).
        """
        if self._job is None:
            return
        if self._sent:
            self._sent = False
            try:
                status, why = self._conn.recv()
            except (EOFError, OSError):  # the process died: the figure is drawn here
                pass
            else:
                if status != "ok":
                    raise RuntimeError(f"calibration figure not written: {why}")
                self._job = None
                return
        from ..report import calibration_figures

        cal, folder = self._job
        self._job = None
        calibration_figures(cal, folder)

    def close(self) -> None:
        """End the process (at once where the command stops before its figure)."""
        if self._proc is None:
            return
        if self._proc.is_alive():
            self._proc.kill()  # not a signal a handler inherited from the command could keep
        self._proc.join()
        self._conn.close()
        self._proc = None

    def __enter__(self) -> FigureProcess:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


@app.command("calibrate")
def calibrate_command(
    study: StudyArg = None,
    out: OutOpt = Path("calibration"),
    H: HOpt = None,
    G: GOpt = None,
    grade: GradeOpt = None,
    standoff: StandoffOpt = None,
    setting: SettingOpt = None,
    silicone: SiliconeOpt = None,
    noise: Annotated[str | None, typer.Option(
        "--noise-uT", metavar="S|X,Z",
        help="RMS field noise [µT] of the Hall chip, one value for both axes or X,Z, for the "
             "resolution sigma_F the firmware map is held to; it replaces the chip's own "
             "figure, and the output says so. Default: the noise of the study's chip at the "
             "design's setting.")] = None,
    presses: Annotated[Path | None, typer.Option(
        "--presses", help="CSV of a built unit's presses (columns B_x_T, B_y_T, B_z_T, F_x_N, "
                          "F_y_N, F_z_N): fit the unit's parameters and export its map.")] = None,
    fit: Annotated[str | None, typer.Option(
        "--fit", help="Comma-separated unit parameters to fit (G_scale, B_scale, "
                      "chip_offset_x/y/z, field_offset_x/y/z); default: G_scale, B_scale and "
                      "the chip offsets.")] = None,
    model_error: Annotated[float | None, typer.Option(
        "--model-error", help="Relative error of the force models (e.g. 0.01), counted in "
                              "the unit fit's weights and conditioning.")] = None,
    force_source: Annotated[str, typer.Option(
        "--force-source", help="Where the map's forces come from: fe (the DOE's FE paths at "
                               "the design's H, interpolated), models (the metamodels) or auto "
                               "(fe for a unit fit with --presses when the data hold the "
                               "design's H, else models).")] = "auto",
    models: ModelsOpt = None,
) -> None:
    """The field-to-force map of the chosen sensor (magtact.calibrate), or of it with the
    parts the options name changed, for firmware: force.h (C99), force_map.json,
    force_table.csv, calibration.json and calibration.png in OUT."""
    from .. import calibrate, design
    from ..calibration import DEFAULT_FIT, read_presses, write_calibration_outputs

    freeze_at_exit()
    s = get_study(study)
    if force_source not in ("auto", "fe", "models"):
        raise MagtactError(f"--force-source must be auto, fe or models, got {force_source!r}")
    if model_error is not None and not 0 <= model_error <= 1:
        raise MagtactError(f"--model-error must be a fraction between 0 and 1, got "
                           f"{model_error}")
    if model_error is not None and presses is None:
        raise MagtactError("--model-error cannot take effect without --presses: it weights the "
                           "unit fit to a built unit's presses; give --presses CSV, or leave "
                           "--model-error out")
    check_sensor_options(s, H=H, G=G, standoff=standoff, setting=setting)
    sigma = None if noise is None else parse_noise(noise)
    units = None if fit is None else fit_names(fit, presses is not None)
    data = None if presses is None else read_presses(presses)
    # the folder is checked (writable, nothing of the user's in the way) before the work; the
    # figure's process ends before the folder's files are put in place (or left)
    with outputs("calibrate", out, "force.h", "force_map.json", "force_table.csv",
                 "calibration.json") as o, FigureProcess() as figure:
        with console.status("choosing the sensor"):
            result = design(s, models=models, log=lambda m: console.print(m, highlight=False))
        sensor, given = chosen_or_given(result, H=H, G=G, grade=grade, standoff=standoff,
                                        setting=setting, silicone=silicone)
        print_sensor_line(sensor, given, console)  # with the command's other messages
        eps = None if model_error is None else (model_error, model_error)
        if sigma is not None:  # says what --noise-uT replaces
            noise_override(sigma)
        with console.status("calibrating: the map, its round trip and the firmware "
                            "candidates"):  # shown in a terminal only
            cal = calibrate(result, sensor if given else None, noise=sigma, presses=data,
                            fit=DEFAULT_FIT if units is None else units, model_error=eps,
                            force_source=force_source)
        figure.draw(cal, o.folder)  # drawn while the other files are written
        write_calibration_outputs(cal, o.folder)
        figure.wait()
    a = cal.firmware.chosen
    console.print(
        f"map: round trip F -> B -> F within {cal.round_trip:.2g} of the force range; "
        f"firmware: {a.kind} ({a.bytes} bytes, {a.multiplies} multiplications), largest "
        f"error F_r {from_si(a.err_r, 'mN'):.3g} mN, F_z {from_si(a.err_z, 'mN'):.3g} mN "
        f"against sigma_F {from_si(cal.sigma_F[0], 'mN'):.3g} / "
        f"{from_si(cal.sigma_F[1], 'mN'):.3g} mN "
        f"({'reached' if cal.firmware.reached else 'NOT reached: see the frontier'})",
        highlight=False)
    e = cal.force_limit
    what = ("the FE paths at H, interpolated; between paths" if cal.map.force_source == "fe"
            else "the metamodels; against the FE paths at H")
    limit = ("not measured (no FE paths at this H)" if e is None or e.F_r is None else
             f"F_r {from_si(e.F_r, 'mN'):.3g} mN, F_z {from_si(e.F_z, 'mN'):.3g} mN")
    console.print(f"forces from {what}: largest error {limit}", highlight=False)
    if cal.unit is not None:
        u = cal.unit.unit
        chip = ", ".join(f"{from_si(v, 'mm'):.4f}" for v in u.chip_offset)
        field = ", ".join(f"{from_si(v, 'mT'):.4f}" for v in u.field_offset)
        console.print(f"unit: G x {u.G_scale:.4f}, remanence x {u.B_scale:.4f}, chip offset "
                      f"({chip}) mm, field offset ({field}) mT", highlight=False)
    console.print(f"wrote {o.out}/force.h, force_map.json, force_table.csv, calibration.json",
                  highlight=False)
