//! Finite-strain implicit finite elements: axisymmetric solids, rigid contact, springs, adaptive time stepping (thesis §2.4, §4.3, §5.3).
