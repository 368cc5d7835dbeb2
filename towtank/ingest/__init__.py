"""Ingest stage: the protocol (``protocol``), the run sheet (``runsheet``) and the run files
(``runfile``: readers, channel mapping and the checks of what was read).
"""
