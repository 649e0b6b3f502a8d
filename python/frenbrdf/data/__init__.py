"""Materials as data: folders and splits, the analytic families and the default bank, published Keras
fits as MERL tables, and per-material NBRDF fitting."""
