"""Other tools a user would otherwise pick, wrapped as solvers (optional extras)."""
