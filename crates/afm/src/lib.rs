//! Measured AFM data: JPK instrument files, calibration, contact point, Hertz and Lee–Radok fits (thesis §1.3.2, §5.2, App. B).
