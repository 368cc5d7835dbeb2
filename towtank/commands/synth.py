"""``towtank synth``: synthetic test days with known truth, from :mod:`towtank.testing`.

The only production module that imports the test tooling: the generator stays out of the
``process`` path, and a lab can still make a day whose truth is known to try towtank on.
"""

from __future__ import annotations

import argparse
from pathlib import Path

EXIT_OK = 0


def synth_command(args: argparse.Namespace) -> int:
    """``towtank synth OUTDIR --day hull|fin|samples``: write a synthetic day (or the samples)."""
    from towtank.testing import synthetic

    if args.day == "samples":
        synthetic.write_sample_days(args.outdir)
        print(f"sample days written to {args.outdir}")
        return EXIT_OK
    hand = args.sheet_format if args.sheet_format in ("hand-xlsx", "hand-csv") else None
    plain = args.sheet_format.removeprefix("hand-") if args.sheet_format else None
    formats = {k: v for k, v in (("file_format", args.file_format),
                                 ("sheet_format", plain)) if v is not None}
    sheet = {"sheet_format": plain} if plain else {}
    if args.day == "hull":
        synthetic.make_hull_day(args.outdir, seed=args.seed, **formats)
        from towtank.testing.layouts import layout_channels, protocol_sections

        layout = args.file_format or ""
        channels = layout_channels(layout, synthetic.LabChannels())
        sections = synthetic.hull_protocol_sections(".", "out", channels=channels, **sheet)
        sections = protocol_sections(layout, sections)
    else:
        synthetic.make_fin_day(args.outdir, seed=args.seed, **formats)
        sections = synthetic.fin_protocol_sections(".", "out", **sheet)
    if hand:  # the same runs, typed as a lab types them
        from towtank.testing.handsheet import write_hand_typed_sheet

        path = Path(args.outdir) / f"run_sheet.{plain}"
        write_hand_typed_sheet(path, hand, path)
    protocol = synthetic.write_protocol(
        Path(args.outdir) / "protocol.toml",
        header=f"Synthetic {args.day} day, seed {args.seed} (towtank synth); truth in truth.json",
        **sections,
    )
    print(f"synthetic {args.day} day written to {args.outdir}; process it with:\n"
          f"  towtank process {protocol}")
    return EXIT_OK
