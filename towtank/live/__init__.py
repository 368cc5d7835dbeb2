"""The tank's live day: run files watched as they arrive, their verdicts, and the page."""
