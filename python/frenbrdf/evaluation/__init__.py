"""Studies: evaluation of trained runs (reconstruction, editing), their tables and statistics,
trained variants, step timing and model selection."""
