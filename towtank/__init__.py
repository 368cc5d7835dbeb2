"""towtank: towing-tank run files to hydrodynamic coefficients, fin data, scaling and reports.

Data flows one way through modules named after the stage of the data's path::

    protocol, runsheet  ->  ingest  ->  conditioning, phases  ->  tare  ->  reduce
        ->  fit (hull), fins  ->  similarity  ->  report

Leaf helpers that any stage may use: ``water`` (ITTC water properties), ``geometry``
(Myring hull), ``sandia`` (NACA 0015 section data), ``errors``.
"""

__version__ = "0.1.0"
