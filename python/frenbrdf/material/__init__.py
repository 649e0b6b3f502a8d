"""A user's material: their measurement files in (CSV/NPZ samples, a MERL table, a ``.bsdf``),
the ``frenbrdf reconstruct`` result folder out."""
