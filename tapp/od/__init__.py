"""The approximate-STM study: batch DC, EKF and R signature over the study file's cases."""
