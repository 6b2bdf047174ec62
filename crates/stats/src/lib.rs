//! Cohort statistics: G(t) per cell and group, Wilcoxon rank-sum tests over time (thesis §5.4.2).
