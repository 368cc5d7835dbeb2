"""Statistics shared by the stages: order statistics and robust scales (``robust``), the
CR2 cluster-robust covariance and the Welch–Satterthwaite degrees of freedom (``intervals``).
"""
