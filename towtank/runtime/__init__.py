"""Runtime helpers that know nothing of hydrodynamics: the reduction cache (``cache``) and the
worker processes (``parallel``).
"""
