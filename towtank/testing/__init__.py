"""Test tooling, never imported by the production path: the synthetic-day generator
(``synthetic``), damaged days (``damage``) and the speed benchmark (``bench``).
"""
