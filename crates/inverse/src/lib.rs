//! Inverse analysis: misfit (eq. 5.3), multistart constrained fits of one or several experiments, identifiability (thesis §3.1, §4.4, §5.4).
