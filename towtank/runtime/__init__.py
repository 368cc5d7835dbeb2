"""Runtime helpers that know nothing of hydrodynamics: the reduction cache (``cache``), the
worker processes (``parallel``), the output folder's checks (``outfolder``) and manifest
(``manifest``), and reading files without trusting them (``safefile``).
"""
