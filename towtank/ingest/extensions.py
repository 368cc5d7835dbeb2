"""The run-file extensions towtank reads (docs/formats.md §3.1), kept apart from the readers so
that the command line can name them without importing numpy."""

from __future__ import annotations

#: Extension → reader format (``[read] format``).
EXTENSIONS = {
    ".csv": "csv", ".txt": "text", ".dat": "text", ".asc": "text", ".tsv": "text",
    ".tdms": "tdms", ".lvm": "lvm", ".mat": "mat", ".h5": "hdf5", ".hdf5": "hdf5",
    ".hdf": "hdf5", ".he5": "hdf5", ".h5m": "hdf5",
}
#: Formats also read gzipped (``run_001.csv.gz``).
GZIP_FORMATS = ("csv", "text", "lvm")


def extensions_text() -> str:
    """Every extension the readers accept, for a command's help:
    ``.csv, .txt, ...; gzipped: .csv.gz, ...``."""
    plain = ", ".join(EXTENSIONS)
    gz = ", ".join(f"{e}.gz" for e, k in EXTENSIONS.items() if k in GZIP_FORMATS)
    return f"{plain}; gzipped: {gz}"
