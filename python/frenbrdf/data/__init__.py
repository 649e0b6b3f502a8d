"""Materials as data: folders and splits, the analytic families and the default bank, material
files of every kind (tables, NBRDF weights, published fits) and per-material NBRDF fitting."""
