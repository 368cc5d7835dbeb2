"""Analysis stage: the day's hull coefficients with their intervals (``hull``), the fins
against the Sandia data (``fins``) and Froude/Reynolds scaling to the prototype
(``similarity``).
"""
