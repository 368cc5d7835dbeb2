"""The ``towtank`` command line (docs/formats.md §4).

Imports of the heavy libraries are deferred to the sub-command that needs them, so that
``towtank --help`` answers at once.
"""

from __future__ import annotations

import argparse
import datetime as dt
import gc
import os
import re
import signal
import sys
import warnings
from pathlib import Path
from typing import Any

from towtank import __version__
from towtank.errors import TowtankError
from towtank.ingest.extensions import extensions_text
from towtank.report.safetext import clean_text
from towtank.runtime.interrupt import handled, watching
from towtank.runtime.pause import pause_at

EXIT_OK, EXIT_REJECTED, EXIT_UNUSABLE, EXIT_BUG = 0, 1, 2, 3

DESCRIPTION = """\
towtank turns a towing tank's raw run files into hydrodynamic coefficients.

Feed it the day's protocol (a TOML file naming the run sheet, the data folder, the model and
the water) and it reduces every run: zero and drift removed, filtered, split into its phases,
sting tare subtracted. It then fits the hull's added mass and damping with 95 % intervals,
compares fins with the Sandia NACA 0015 data, scales to the full-size vehicle and writes CSV
tables, an Excel workbook and a PDF report.
"""

EPILOG = """\
examples:
  towtank process protocols/sut2_hull.toml           reduce the sample hull day
  towtank process day3.toml --out reports/day3 -j 2  choose the output folder and cores
  towtank inspect sample_runs/sut2_hull/data/run_005.csv.gz --protocol protocols/sut2_hull.toml
  towtank scale protocols/sut2_hull.toml --speeds 1 2 3
  towtank watch day3.toml --no-browser               verdict per run while the tank runs
  towtank synth /tmp/day --day hull                  generate a synthetic test day
  towtank predict protocols/remus_vehicle.toml --out pred      [vehicle] coefficients, model.json
  towtank simulate pred/model.json --manoeuvre turning --rudder-deg 10
  towtank simulate pred/model.json --manoeuvre sine --rudder-deg 10 --period-s 20 --out sine
  towtank identify pred/model.json sine/manoeuvre.csv --estimate N_ur,N_rdot,N_uudr
  towtank predict protocols/glider_parametric.toml --out glider  a glider's model.json
  towtank steady glider/model.json --ballast-cc -200,-450 --pitch-deg -45:-5:5

exit status of 'process': 0 every run usable; 1 finished but some runs were rejected (listed
in runs.csv); 2 the protocol or run sheet is unusable, or the output folder cannot be written
(nothing written, previous outputs untouched); 3 internal error; 130 interrupted (Ctrl-C).
The other commands: 0 done, 2 unusable input or output folder, 3 internal error, 130.
'watch' stopped by SIGTERM or SIGHUP: 143 or 129 (its page server stops with it).
"""


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="towtank",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--version", action="version", version=f"towtank {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")

    pr = sub.add_parser(
        "process",
        help="reduce a test day and write its tables and reports",
        description="Reduce every run of the protocol's run sheet and write coefficients.csv, "
        "runs.csv, fins.csv, fin_curves.csv and fin_control.csv (fin days), scaling.csv, "
        "tare.csv, pmm.csv (captive days), report.xlsx, report.pdf, figures/ and "
        "provenance.json; with a [vehicle] "
        "section also predicted.csv and model.json; with --export, export/. The per-run "
        "cache is kept in .cache/ and the manifest of what towtank wrote in "
        ".towtank-outputs.json.",
    )
    pr.add_argument("protocol", type=Path, help="the campaign's protocol file (.toml)")
    _day_options(pr, jobs_help="runs reduced in parallel, and the report's parts drawn "
                 "beside each other (default: the protocol's [processing] jobs, else "
                 "$TOWTANK_JOBS, else all cores; 1: everything in this one process)")
    pr.add_argument("--export", action="append",
                    choices=("mat", "hdf5", "parquet", "simman"), default=None,
                    metavar="FORMAT",
                    help="also write every usable run's reduced time series (zeroed, filtered, "
                    "tared, with its phases) into DIR/export/: mat (MATLAB), hdf5 or parquet; "
                    "simman: the captive tests (static means, PMM periods with their Fourier "
                    "coefficients, particulars) into DIR/export/simman/; "
                    "may be given more than once")
    pr.add_argument("--quiet", "-q", action="store_true", help="no progress bar, no summary")
    pr.add_argument("--no-cache", action="store_true",
                    help="ignore and rebuild the per-run cache in the output folder")
    _debug_option(pr)

    wa = sub.add_parser(
        "watch",
        help="process the day run by run while the tank runs: a verdict per run, a live page",
        description="Give every run of the sheet whose file is complete a verdict line (run, "
        "test, angle, speed, drag, status and, for a rejected or suspicious run, the reason), "
        "then watch the data folder and the run sheet: each new, changed or re-recorded run "
        "file gets its verdict once its writer has closed it (or it has not changed for "
        "[watch] settle_s), and the outputs of 'process' are brought up to date (the PDF and "
        "figures at most every [watch] pdf_interval_s). The live state for the browser page "
        "is in DIR/.live/. Ctrl-C stops it (exit 130; SIGTERM 143, SIGHUP 129); the output "
        "folder then holds the last complete set.",
    )
    wa.add_argument("protocol", type=Path, help="the campaign's protocol file (.toml)")
    wa.add_argument("--port", type=_port, default=8050, metavar="N",
                    help="port of the live page on 127.0.0.1 (default 8050)")
    wa.add_argument("--no-browser", action="store_true", help="do not open the page")
    wa.add_argument("--no-server", action="store_true",
                    help="no page server (verdict lines and outputs only)")
    _day_options(wa, jobs_help="runs reduced in parallel when several arrive at once, and "
                 "the report's pages drawn beside each other (default: the protocol's "
                 "[processing] jobs, else $TOWTANK_JOBS, else all cores; 1: one process "
                 "drawing)")
    wa.add_argument("--quiet", "-q", action="store_true", help="no start-up line")
    _debug_option(wa)

    ins = sub.add_parser(
        "inspect",
        help="quick look at one run file: phases, means and a plot",
        description="Read one run file, find its phases and print them with the steady means "
        "(zero and drift removed, no tare); write a PNG of speed and forces with the phases "
        "shaded. Without --protocol, a file whose channels are not named time, speed, drag, "
        "lift is described (format, timing, channels, units) and a [read]/[channels] block "
        "for the protocol is proposed (load cells of one force summed with columns = [...], "
        "a volt channel at a provisional gain = 1.0); the run is then reduced with that "
        "block.",
    )
    ins.add_argument("runfile", type=Path,
                     help="a run file in any format process reads: "
                     f"{extensions_text()}; or any name with [read] format in the protocol")
    ins.add_argument("--protocol", type=Path,
                     help="protocol whose [read], [channels], [balance], [speed_log], [zeros] "
                     "and [processing] apply, as in process")
    ins.add_argument("--png", type=Path,
                     help="where to write the plot (default: <run file name>.png in the "
                     "current folder)")
    ins.add_argument("--debug", action="store_true", help=argparse.SUPPRESS)

    sc = sub.add_parser(
        "scale",
        help="print the model-to-prototype scaling table",
        description="Print the Froude and Reynolds scaling of the campaign's zero-angle "
        "resistance to the prototype (uses the cached reduction in the output folder).",
    )
    sc.add_argument("protocol", type=Path)
    sc.add_argument("--speeds", type=float, nargs="+", metavar="U",
                    help="prototype speeds [m/s] (default: [prototype] speeds_m_s)")
    sc.add_argument("--out", type=Path, metavar="DIR", help="output folder holding the cache")
    sc.add_argument("--debug", action="store_true", help=argparse.SUPPRESS)

    pd_ = sub.add_parser(
        "predict",
        help="predict the coefficients of the protocol's [vehicle] from its geometry",
        description="Write predicted.csv (symbol, value, unit, prime, method, reference) and "
        "model.json for the hull and fins described in the protocol's [vehicle] section; with "
        "[vehicle.propeller] also powering.csv (effective power, B-series propeller: rps, "
        "torque, efficiency, delivered power over speeds), with [vehicle.pressure_hull] also "
        "pressure_hull.csv (wall thickness for yield and von Mises buckling).",
    )
    pd_.add_argument("protocol", type=Path)
    pd_.add_argument("--out", type=Path, metavar="DIR",
                     help="output folder (default: output_dir of the protocol)")
    pd_.add_argument("--debug", action="store_true", help=argparse.SUPPRESS)

    si = sub.add_parser(
        "simulate",
        help="simulate a manoeuvre of a model.json (turning, zigzag, dive, spiral, glide)",
        description="6-DOF simulation of the Fossen-form model written by 'predict' or "
        "'process': manoeuvre.csv (time series), metrics.csv and manoeuvre.png; a glide also "
        "glide_table.csv (the steady glides around it).",
    )
    si.add_argument("model", type=Path, help="model.json")
    si.add_argument("--manoeuvre", required=True,
                    choices=("turning", "zigzag", "dive", "spiral", "glide", "sine",
                             "schedule"),
                    help="sine: rudder A sin(2 pi t/T) (--rudder-deg A, --period-s T); "
                    "schedule: the controls of --schedule FILE")
    si.add_argument("--rudder-deg", type=float, metavar="D",
                    help="rudder angle (zigzag: also the check angle) [deg]")
    si.add_argument("--sternplane-deg", type=float, metavar="D", help="stern-plane angle [deg]")
    si.add_argument("--speed", type=float, metavar="U",
                    help="speed [m/s] (default: the model's design speed)")
    si.add_argument("--net-buoyancy-N", type=float, metavar="B", dest="net_buoyancy",
                    help="buoyancy minus weight [N] (default: the model's)")
    si.add_argument("--duration-s", type=float, metavar="T", help="simulated time [s]")
    si.add_argument("--dive-angle-deg", type=float, metavar="A", dest="dive_angle",
                    help="dive: hold this pitch, nose down, with the stern planes (PD law) [deg]")
    si.add_argument("--roll-deg", type=float, metavar="R", dest="roll_deg",
                    help="glide: roll the glider by its roll mass ([vehicle.glider]), "
                    "starboard down positive [deg]")
    si.add_argument("--period-s", type=float, metavar="T", dest="period_s",
                    help="sine: the rudder's period [s] (default 10)")
    si.add_argument("--schedule", type=Path, metavar="FILE",
                    help="schedule: CSV of t_s, rudder_deg, sternplane_deg (interpolated)")
    si.add_argument("--noise", metavar="STATE=SD,...",
                    help="add Gaussian noise to manoeuvre.csv's states, e.g. "
                    "u=0.01,r=0.2,psi=0.5 (the column's unit: m, deg, m/s, deg/s)")
    si.add_argument("--seed", type=int, default=1,
                    help="seed of --noise and of --samples' draws (default 1)")
    si.add_argument("--sample-hz", type=float, metavar="F", dest="sample_hz",
                    help="write manoeuvre.csv at this rate [Hz] (default: the integrator's "
                    "steps)")
    si.add_argument("--propeller", choices=("thrust", "rps"), default="thrust",
                    help="propulsion: a constant thrust (default), or the model's B-series "
                    "propeller ([vehicle.propeller]) at the constant rps of its "
                    "self-propulsion point at the start speed")
    si.add_argument("--samples", type=int, default=0, metavar="N",
                    help="draw the measured coefficients N times for 95 %% bands")
    si.add_argument("--out", type=Path, metavar="DIR",
                    help="output folder (default: ./simulate_<manoeuvre>)")
    si.add_argument("--debug", action="store_true", help=argparse.SUPPRESS)

    st = sub.add_parser(
        "steady",
        help="a glider's steady glides and spirals over lists of ballast, pitch and roll",
        description="The steady glide (roll 0) and steady spiral of a model.json with a "
        "'glider' block ([vehicle.glider]) for every ballast, pitch and roll, with the moving "
        "mass's travel and the roll mass's angle that hold them: steady.csv and steady.png. "
        "Lists: -200,-300,-450 or start:stop:step (-45:-5:5).",
    )
    st.add_argument("model", type=Path, help="model.json")
    st.add_argument("--ballast-cc", required=True, metavar="LIST", dest="ballast_cc",
                    help="pumped volume from neutral [cc], negative heavy (descent)")
    st.add_argument("--pitch-deg", required=True, metavar="LIST", dest="pitch_deg",
                    help="pitch, nose up positive [deg]")
    st.add_argument("--roll-deg", metavar="LIST", dest="roll_deg",
                    help="roll, starboard down positive [deg] (default 0: glides only)")
    st.add_argument("--out", type=Path, metavar="DIR",
                    help="output folder (default: ./steady)")
    st.add_argument("--debug", action="store_true", help=argparse.SUPPRESS)
    # lists such as -200,-300 or -45:-5:5 are values, not options
    st._negative_number_matcher = re.compile(r"^-[\d.eE:,+-]+$")
    idn = sub.add_parser(
        "identify",
        help="identify coefficients of a model.json from a manoeuvre record (Kalman filter "
        "and smoother, checked by least squares)",
        description="Augmented-state unscented (or extended) Kalman filter with the 6-DOF "
        "model of 'simulate', a Rauch-Tung-Striebel smoother and output-error least squares "
        "as the cross-check: identified.csv, model.json (the identified values, sources "
        "'identified', their covariance), identify.png and fit.csv (whether the record fits "
        "the model; exit 1 and the verdict 'model does not fit' when it does not) in --out; "
        "one verdict line per coefficient.",
    )
    idn.add_argument("model", type=Path, help="model.json")
    idn.add_argument("log", type=Path, help="manoeuvre record (CSV in simulate's columns)")
    idn.add_argument("--estimate", required=True, metavar="SYMBOLS",
                     help="coefficients to identify, comma-separated (N_ur,N_rdot,N_uudr)")
    idn.add_argument("--method", choices=("ukf", "ekf", "ls"), default="ukf",
                     help="unscented (default) or extended Kalman filter and smoother, or "
                     "least squares alone")
    idn.add_argument("--start", choices=("model", "zero"), default="model",
                     help="starting values: the model's (default) or zero")
    idn.add_argument("--protocol", type=Path, metavar="TOML",
                     help="a protocol whose [channels] maps the record's column names")
    idn.add_argument("--noise", metavar="STATE=SD,...", type=_noise_option,
                     help="measurement noise per state, each named once with a standard "
                     "deviation > 0 (default: estimated from the record)")
    idn.add_argument("--validate", type=Path, metavar="LOG2",
                     help="a second record the identified model is tested against (default: "
                          "the record's last quarter, held out of a least-squares refit)")
    idn.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    idn.add_argument("--out", type=Path, metavar="DIR",
                     help="output folder (default: ./identify)")
    idn.add_argument("--debug", action="store_true", help=argparse.SUPPRESS)

    sy = sub.add_parser(
        "synth",
        help="generate a synthetic test day (for training, testing and benchmarks)",
        description="Write a synthetic day: run files, run sheet, protocol and truth.json.",
    )
    sy.add_argument("outdir", type=Path,
                    help="folder to write into (created; must be empty unless --force)")
    sy.add_argument("--day", choices=("hull", "fin", "air", "captive", "captive-vertical",
                                      "samples"), default="hull",
                    help="hull day, fin day, the hull day in air (a wind tunnel at 2-40 m/s, "
                    "[water] type = \"air\", a 1 kg model), a captive manoeuvring day of "
                    "REMUS (static drift, rudder, rotating arm, PMM; captive-vertical: the "
                    "model rolled 90 degrees for the heave-pitch derivatives), or regenerate "
                    "both shipped sample days")
    sy.add_argument("--seed", type=int, default=1,
                    help="seed of the random noise: the same seed gives the same files "
                    "(default 1)")
    sy.add_argument("--format", choices=("csv", "csv.gz", "tdms", "tdms-waveform", "lvm",
                                         "txt-eu", "mat", "mat73", "hdf5",
                                         "hdf5-rate-name", "two-cell",
                                         "matrix", "speed-log", "position-log", "zero-file",
                                         "no-speed", "lvm-appended"),
                    default=None, dest="file_format",
                    help="run-file format (default: csv.gz for the hull day, tdms for the fin "
                    "day); tdms-waveform (LabVIEW timing, no time channel), lvm, txt-eu "
                    "(';' and decimal commas, preamble, units row), mat (v5), mat73, hdf5, "
                    "hdf5-rate-name (MARIN-style: the rate only in the group's name, .h5m), "
                    "two-cell (DragL + DragR), matrix (a 2x2 interaction matrix), speed-log and "
                    "position-log (carriage speed or position in its own file per run, 100 Hz, "
                    "another clock), zero-file (a zeros file per run), no-speed (no speed "
                    "channel: the sheet's set speed and steady windows), lvm-appended (two "
                    "acquisitions under one LVM header, the run the second: the sheet's "
                    "segment column) are other labs' layouts")
    sy.add_argument("--sheet", choices=("csv", "xlsx", "hand-xlsx", "hand-csv"), default=None,
                    dest="sheet_format",
                    help="run-sheet format (default: xlsx for the hull day, csv for the fin "
                    "day); hand-xlsx and hand-csv are typed as a lab types them (title row, "
                    "the lab's column names and status words, notes below; hand-csv is ';' "
                    "separated with decimal commas and the speed in mm/s)")
    sy.add_argument("--force", action="store_true",
                    help="write into a folder that is not empty, replacing the files an earlier "
                    "synth wrote there (never a file synth did not write)")
    sy.add_argument("--debug", action="store_true", help=argparse.SUPPRESS)
    return p


def _day_options(parser: argparse.ArgumentParser, *, jobs_help: str) -> None:
    """The options ``process`` and ``watch`` share: --out, --no-report, --jobs, --date."""
    parser.add_argument("--out", type=Path, metavar="DIR",
                        help="output folder (default: output_dir of the protocol)")
    parser.add_argument("--no-report", action="store_true",
                        help="write the CSV tables only (no workbook, PDF or figures)")
    parser.add_argument("--jobs", "-j", type=_jobs, metavar="N", help=jobs_help)
    parser.add_argument("--date", metavar="YYYY-MM-DD", type=_iso_date,
                        help="test date printed in the report (default: from the inputs)")


def _debug_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--debug", action="store_true",
                        help="show a traceback for internal errors instead of one sentence")


def _iso_date(text: str) -> str:
    """``--date``: a date that exists, written YYYY-MM-DD."""
    try:
        return dt.datetime.strptime(text.strip(), "%Y-%m-%d").date().isoformat()
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a date that exists, written YYYY-MM-DD") from None


def _jobs(text: str) -> int:
    """``--jobs``: a whole number of at least 1."""
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number of at least 1")
    return n


def _port(text: str) -> int:
    """``--port``: a TCP port, 1-65535."""
    try:
        n = int(text)
    except ValueError:
        n = 0
    if not 1 <= n <= 65535:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port (a whole number 1-65535)")
    return n


def _err(msg: str) -> None:
    print(f"towtank: {clean_text(msg)}", file=sys.stderr)


def cmd_process(args: argparse.Namespace) -> int:
    """``towtank process``: the day run by :func:`towtank.runner.run_day`, its notes on the
    error stream and its summary on the output."""
    # loaded on use: the runner loads the protocol's checks and, when the day runs, every stage
    from towtank.runner import DayStopped, Options, run_day

    bar = _progress_bar() if not args.quiet and sys.stderr.isatty() else None

    def progress(done: int, total: int) -> None:
        if bar is not None:
            bar.total = total
            bar.update(done - bar.n)

    options = Options(report=not args.no_report, export=tuple(args.export or ()),
                      date=args.date, cache=not args.no_cache, jobs=args.jobs,
                      debug=args.debug, quiet=args.quiet, progress=progress)
    try:
        run = run_day(args.protocol, args.out, options)
    except DayStopped as exc:
        for note in exc.notes:
            _err(note)
        _err(str(exc))
        return EXIT_UNUSABLE
    finally:
        if bar is not None:
            bar.close()
    for note in run.notes:
        _err(note)
    if not args.quiet:
        print(run.summary.rstrip("\n"))
    return run.code


def _progress_bar() -> Any:
    """The progress bar of the runs reduced, on the terminal's error stream."""
    # loaded on use: tqdm only for a progress bar on a terminal
    from tqdm import tqdm

    # no monitor thread: the report's writers fork, which is only safe with one thread
    tqdm.monitor_interval = 0
    return tqdm(total=0, unit="run", desc="reducing", file=sys.stderr, leave=False)


def cmd_inspect(args: argparse.Namespace) -> int:
    # loaded on use: a command's modules are loaded when it runs (towtank --help loads none of them)
    from towtank.commands.inspect import inspect_run

    return inspect_run(args.runfile, protocol_path=args.protocol, png=args.png)


def cmd_scale(args: argparse.Namespace) -> int:
    # loaded on use: a command's modules are loaded when it runs (towtank --help loads none of them)
    from towtank.commands.scale import scale_command

    return scale_command(args.protocol, speeds=args.speeds, out=args.out)


def cmd_synth(args: argparse.Namespace) -> int:
    # loaded on use: a command's modules are loaded when it runs (towtank --help loads none of them)
    from towtank.commands.synth import synth_command

    return synth_command(args)


def cmd_predict(args: argparse.Namespace) -> int:
    # loaded on use: a command's modules are loaded when it runs (towtank --help loads none of them)
    from towtank.commands.predict import predict_command

    return predict_command(args.protocol, out=args.out)


def cmd_simulate(args: argparse.Namespace) -> int:
    # loaded on use: a command's modules are loaded when it runs, so that towtank --help and the
    # other commands start in ~50 ms
    from towtank.commands.simulate import simulate_command

    return simulate_command(
        args.model, args.manoeuvre, rudder_deg=args.rudder_deg,
        sternplane_deg=args.sternplane_deg, speed=args.speed,
        net_buoyancy_n=args.net_buoyancy, out=args.out, samples=args.samples,
        duration_s=args.duration_s, dive_angle_deg=args.dive_angle, roll_deg=args.roll_deg,
        seed=args.seed, period_s=args.period_s, schedule=args.schedule, noise=args.noise,
        sample_hz=args.sample_hz, propeller=args.propeller)


def cmd_steady(args: argparse.Namespace) -> int:
    # loaded on use: a command's modules are loaded when it runs (towtank --help loads none of them)
    from towtank.commands.steady import steady_command

    return steady_command(args.model, args.ballast_cc, args.pitch_deg, args.roll_deg,
                          out=args.out)



def cmd_identify(args: argparse.Namespace) -> int:
    # loaded on use: a command's modules are loaded when it runs (towtank --help loads none of them)
    from towtank.commands.identify import identify_command

    return identify_command(args.model, args.log, args.estimate, method=args.method,
                            start=args.start, out=args.out, protocol=args.protocol,
                            noise=args.noise, quiet=args.quiet, validate=args.validate)


def _noise_option(text: str) -> dict[str, float]:
    """identify's --noise, read by the parser (its error the parser's usage line)."""
    # loaded on use: identify's modules are loaded only when the option is given
    from towtank.commands.identify import noise_option

    return noise_option(text)


def cmd_watch(args: argparse.Namespace) -> int:
    # loaded on use: a command's modules are loaded when it runs (towtank --help loads none of them)
    from towtank.commands.watch import watch_command

    return watch_command(args)


COMMANDS = {
    "watch": cmd_watch,
    "steady": cmd_steady,
    "predict": cmd_predict,
    "simulate": cmd_simulate,
    "identify": cmd_identify,
    "process": cmd_process,
    "inspect": cmd_inspect,
    "scale": cmd_scale,
    "synth": cmd_synth,
}


def main(argv: list[str] | None = None) -> int:
    with watching() as interrupted:  # first: a Ctrl-C from here on is one line, exit 130
        try:
            pause_at("start")
            parser = _parser()
            args = parser.parse_args(argv)
        except KeyboardInterrupt:
            return _interrupted()
        if args.command is None:
            parser.print_help()
            return EXIT_UNUSABLE
        if not getattr(args, "debug", False):
            warnings.showwarning = _warning_line
        return _run(args, interrupted)


def _run(args: argparse.Namespace, interrupted: list[bool]) -> int:
    try:
        return COMMANDS[args.command](args)
    except TowtankError as exc:
        _err(str(exc))
        return EXIT_UNUSABLE
    except KeyboardInterrupt:
        return _interrupted()
    except BrokenPipeError:
        raise  # the output's reader went away (| head): entry() ends quietly
    except Exception as exc:  # noqa: BLE001 - one sentence, not a traceback, for users
        if interrupted:  # a library stopped by Ctrl-C (zlib mid-flush...): not a bug
            return _interrupted()
        if getattr(args, "debug", False):
            raise
        _err(
            f"internal error ({type(exc).__name__}: {exc}); nothing was written. "
            "Rerun with --debug for the traceback and please report it."
        )
        return EXIT_BUG


def _warning_line(message: Warning | str, category: type[Warning], filename: str,
                  lineno: int, file: object = None, line: str | None = None) -> None:
    """Python warnings on the terminal: towtank's own as one line without a source path;
    the libraries' (matplotlib, npTDMS, numpy...) not at all, their effects are the day's
    warnings and notes (``--debug`` shows everything)."""
    if not category.__module__.startswith("towtank"):
        return
    first = str(message).strip().splitlines()[0] if str(message).strip() else category.__name__
    _err(f"warning: {first}")


EXIT_INTERRUPTED = 130  # 128 + SIGINT, the shell's convention
INTERRUPTED = ("interrupted; the output folder holds the outputs of the last complete run "
               "(or none), never a part of this one.")


def _interrupted() -> int:
    """Ctrl-C: its one sentence; further Ctrl-C are ignored while the process ends."""
    handled()
    _err(INTERRUPTED)
    return EXIT_INTERRUPTED


def entry() -> None:
    """The ``towtank`` console command: :func:`main`, then exit with its status.

    Before exiting, the objects still alive are frozen out of the garbage collector
    (``gc.freeze``): the interpreter's final collections over the hundreds of thousands of
    objects that pandas, scipy and statsmodels create at import would otherwise take about
    0.2 s, a tenth of a day's processing, for memory the system frees anyway.
    """
    try:
        code = main()
        sys.stdout.flush()
        if code == EXIT_INTERRUPTED:  # said so: another Ctrl-C must not stop the exit midway
            signal.signal(signal.SIGINT, signal.SIG_IGN)
    except BrokenPipeError:  # `towtank inspect … | head`: the reader has all it wanted
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # no second error when Python flushes at exit
        code = EXIT_OK
    gc.freeze()
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    entry()
