"""Reproductions of the seed documents' experiments, each a module with ``run(out_dir) -> dict``."""
