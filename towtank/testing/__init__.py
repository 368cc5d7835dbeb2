"""Test tooling, never imported by the production path: the synthetic-day generator
(``synthetic``), damaged days (``damage``), the speed benchmark (``bench``) and the test run's
cost by test (``suitecost``, a pytest plugin).
"""
