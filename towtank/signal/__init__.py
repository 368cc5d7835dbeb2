"""Signal stage: conditioning of one run's channels (filter, zero, drift: ``conditioning``),
its phases from the speed (``phases``) and boolean-mask helpers (``masks``).
"""
