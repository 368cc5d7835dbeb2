"""The tank's live day (``towtank watch``): when a run file is complete (arrival), the watch
loop (session), the live state the page server reads (state). docs/formats.md §4.1."""
