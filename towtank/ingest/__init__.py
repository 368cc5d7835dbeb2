"""Ingest stage: the protocol, the run sheet and the run files.

In the order the data takes:

- ``protocol_types``: the frozen types of a validated protocol (the leaf of the configuration);
- ``schema``, ``sections``, ``sheetlayout``, ``vehicle_protocol``, ``design_inputs``: the section
  parsers, which build those types from the TOML file; ``protocol``: ``load_protocol``;
- ``runsheet``: the run sheet;
- ``readers``, ``plaincsv``, ``arrayfiles``, ``columns``: a run file's bytes and columns in its
  format; ``speedlog`` and ``zerofile``: a carriage log's and a zeros file's;
- ``runfile``: a run's channels mapped, calibrated and checked (``calibration``, ``timing``,
  ``segments``); ``describe``: what an unknown file holds (``towtank inspect``).
"""
