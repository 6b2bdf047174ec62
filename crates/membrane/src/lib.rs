//! Semi-analytical solver for a fluid-filled NLV membrane squeezed between rigid plates (thesis ch. II §2.3, App. C).
