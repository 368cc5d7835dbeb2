"""Reduce stage: one run's reduction to steady and accelerated means (``run``) and the sting
tare models (``tare``).
"""
