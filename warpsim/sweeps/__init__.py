"""Parameter sweeps: the metric catalogue, the plan of cases and chunks, the chunk runner, the table and its
journal, the Dask cluster and the plot of a finished table."""

from .plan import METRICS, SweepError, SweepPlan, sweep

__all__ = ["METRICS", "SweepError", "SweepPlan", "sweep"]
