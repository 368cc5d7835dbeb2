"""``towtank synth``: synthetic test days with known truth, from :mod:`towtank.testing`.

The only production module that imports the test tooling: the generator stays out of the
``process`` path, and a lab can still make a day whose truth is known to try towtank on.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
from pathlib import Path

from towtank.runtime import manifest
from towtank.testing import synthetic
from towtank.testing.captive import make_captive_day
from towtank.testing.handsheet import write_hand_typed_sheet
from towtank.testing.layouts import LAYOUTS, layout_channels, protocol_sections

EXIT_OK, EXIT_UNUSABLE = 0, 2

#: The files a synth run wrote in its folder (and their digests): only those may be replaced.
SYNTH_MANIFEST = ".towtank-synth.json"


def synth_command(args: argparse.Namespace) -> int:
    """``towtank synth OUTDIR``: write a synthetic day (or the samples) into OUTDIR.

    A folder that is not empty is refused unless ``--force``; even then a file synth did not
    write there (its manifest says which) is never replaced: the day is made in a temporary
    folder beside OUTDIR and moved in only when nothing foreign would be overwritten.
    """
    out = Path(args.outdir).resolve()
    if out.exists() and not out.is_dir():
        return _refuse(f"{out} is a file, not a folder.")
    if out.is_dir() and any(out.iterdir()) and not getattr(args, "force", False):
        return _refuse(f"{out} is not empty; synth writes a whole day (data/, run sheet, "
                       "protocol.toml, truth.json): choose an empty or new folder, or add "
                       "--force to replace an earlier synthetic day there (files synth did "
                       "not write are never replaced).")
    out.parent.mkdir(parents=True, exist_ok=True)
    with manifest.output_lock(out):  # one writer of the folder at a time
        return _write_day(args, out)


def _write_day(args: argparse.Namespace, out: Path) -> int:
    """Make the day in a temporary folder beside ``out`` and move it in, never over a file
    synth did not write; the exit status."""
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.synth-", dir=out.parent))
    try:
        text = _generate(args, tmp, out)
        made = manifest.describe(tmp, {p.name for p in tmp.iterdir()})
        old = _synth_files(out)
        clash = sorted(rel for rel in made if os.path.lexists(out / rel) and (
            (out / rel).is_symlink() or not manifest.known(out / rel, old.get(rel, []))))
        if clash:
            more = f" and {len(clash) - 5} more" if len(clash) > 5 else ""
            return _refuse(f"{out} holds {', '.join(clash[:5])}{more}, which synth did not "
                           "write (or which was changed since); nothing was written.")
        out.mkdir(exist_ok=True)
        for rel in sorted(made):
            (out / rel).parent.mkdir(parents=True, exist_ok=True)
            os.replace(tmp / rel, out / rel)
        manifest.write_manifest(out, {**old, **manifest.describe(out, set(made))})
        os.replace(out / manifest.MANIFEST, out / SYNTH_MANIFEST)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print(text)
    return EXIT_OK


def _refuse(sentence: str) -> int:
    print(f"towtank: synth: {sentence}", file=sys.stderr)
    return EXIT_UNUSABLE


def _synth_files(out: Path) -> dict:
    """The files an earlier synth run wrote in ``out`` (from its manifest, checked as the
    outputs' manifest is: :func:`towtank.runtime.manifest.read_manifest`)."""
    data = manifest.read_manifest(out, SYNTH_MANIFEST)
    return dict(data["files"]) if data else {}


def _generate(args: argparse.Namespace, tmp: Path, out: Path) -> str:
    """Write the day into ``tmp``; the message to print once it is in ``out``."""
    if args.day == "samples":
        synthetic.write_sample_days(tmp)
        return f"sample days written to {out}"
    if args.day.startswith("captive"):
        return _captive_day(args, tmp)
    hand = args.sheet_format if args.sheet_format in ("hand-xlsx", "hand-csv") else None
    plain = args.sheet_format.removeprefix("hand-") if args.sheet_format else None
    formats = {k: v for k, v in (("file_format", args.file_format),
                                 ("sheet_format", plain)) if v is not None}
    sheet = {"sheet_format": plain} if plain else {}
    if args.day == "air":  # the hull day in air: its layouts as the hull day's
        synthetic.make_air_hull_day(tmp, seed=args.seed, **formats)
        layout = args.file_format or ""
        channels = layout_channels(layout, synthetic.LabChannels())
        sections = synthetic.air_protocol_sections(".", "out", channels=channels, **sheet)
        sections = protocol_sections(layout, sections)
    elif args.day == "hull":
        synthetic.make_hull_day(tmp, seed=args.seed, **formats)
        layout = args.file_format or ""
        channels = layout_channels(layout, synthetic.LabChannels())
        sections = synthetic.hull_protocol_sections(".", "out", channels=channels, **sheet)
        sections = protocol_sections(layout, sections)
    else:  # a lab's layout records the lab's channel names, which [channels] then maps
        layout = args.file_format if args.file_format in LAYOUTS else ""
        synthetic.make_fin_day(tmp, seed=args.seed, **formats,
                               channel_style="lab" if layout else "canonical")
        sections = synthetic.fin_protocol_sections(".", "out", **sheet)
        if layout:
            channels = layout_channels(layout, synthetic.LabChannels())
            sections = protocol_sections(layout, {
                **sections, "channels": channels.protocol_section()})
    if hand:  # the same runs, typed as a lab types them
        path = Path(tmp) / f"run_sheet.{plain}"
        write_hand_typed_sheet(path, hand, path)
    protocol = synthetic.write_protocol(
        Path(tmp) / "protocol.toml",
        header=f"Synthetic {args.day} day, seed {args.seed} (towtank synth); truth in truth.json",
        **sections,
    )
    return (f"synthetic {args.day} day written to {args.outdir}; process it with:\n"
            f"  towtank process {Path(args.outdir) / protocol.name}")


def _captive_day(args: argparse.Namespace, tmp: Path) -> str:
    """A captive manoeuvring day of REMUS (:func:`towtank.testing.captive.make_captive_day`)
    with its truth in truth.json; the message to print."""
    plane = "vertical" if args.day == "captive-vertical" else "horizontal"
    layout = {"lvm": "lvm", "tdms-waveform": "tdms-waveform", "tdms": "tdms-waveform"}.get(
        args.file_format or "", "csv-units")
    make_captive_day(tmp, seed=args.seed, layout=layout, plane=plane)  # with truth.json
    return (f"synthetic {args.day} day written to {args.outdir}; process it with:\n"
            f"  towtank process {Path(args.outdir) / 'protocol.toml'}")

