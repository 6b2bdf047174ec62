//! Design of experiments (Latin hypercube) and DACE-equivalent Kriging surrogates with checking errors (thesis ch. III, §4.4.1).
