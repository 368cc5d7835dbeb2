"""Reference data every stage may consult: ITTC water properties (``water``), the Sandia
NACA 0015 section table (``sandia``), hull geometry (``geometry``) and the packaged reference
coefficient sets (``data/``).
"""
