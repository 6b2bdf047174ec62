//! Loading programs and time grids: step, ramp-hold, ramp-reverse, the AFM two-step script (thesis §4.2, §5.2.2, Fig. 5.2), tabulated histories.
