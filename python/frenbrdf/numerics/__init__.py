"""Numerics: thin wrappers over the Rust core — Rusinkiewicz coordinates, kNN interpolation on the
sphere, the spherical harmonic transform and its torch op. Nothing here knows about materials."""
