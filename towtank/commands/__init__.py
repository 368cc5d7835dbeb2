"""The ``towtank`` command line: ``cli`` (process, synth and the parser), ``inspect`` and
``scale``.
"""
