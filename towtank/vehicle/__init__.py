"""The vehicle stage: coefficients predicted from hull geometry (``hull``, ``predict``), the
Fossen-form manoeuvring model (``model``) and manoeuvres simulated from it (``simulate``).
"""
