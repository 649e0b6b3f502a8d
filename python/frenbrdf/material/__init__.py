"""A user's material: ``frenbrdf reconstruct``'s result folder from a measurement file
(read by :func:`frenbrdf.io.read_samples`), and ``frenbrdf convert`` between its formats."""
