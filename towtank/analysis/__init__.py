"""Analysis stage: each run's C_D, C_L, Re and Fn (``run_coefficients``), the day's hull
coefficients with their intervals (``hull``), the fins against the Sandia data (``fins``,
chained for a day by ``fin_analysis``) and Froude/Reynolds scaling to the prototype
(``similarity``, chained for a day by ``scaling``). Each day-level function returns its result
and its warnings; none changes another stage's result.
"""
