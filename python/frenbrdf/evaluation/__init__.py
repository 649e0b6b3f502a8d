"""Evaluation of trained runs: reconstruction and editing tables, their statistics over seeds, power spectra,
trained variants of the FreNBRDF preset, and model selection (``frenbrdf evaluate``, ``spectrum``, ``select``)."""
