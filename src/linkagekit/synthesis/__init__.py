"""Dimensional synthesis: design spaces, objectives over (designs x samples), optimizers, checkpoints.

Nothing heavy is imported here; :func:`linkagekit.synthesis.run.synthesize` is the entry point.
"""
