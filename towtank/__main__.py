"""``python -m towtank``: the same command line as the ``towtank`` script."""

from towtank.commands.cli import entry

if __name__ == "__main__":
    entry()
