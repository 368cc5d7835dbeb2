"""The tank's live day (``towtank watch``): when a run file is complete (arrival), the watch
loop (session), the live state (state) and the page that shows it (server, static/)."""
