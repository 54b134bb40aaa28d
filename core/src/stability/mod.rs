//! Woodhouse's linearised stability analysis of Helmholtz motion (seed 001, sections 2–3).
