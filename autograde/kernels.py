"""The kernel manager nbgrader is given while grading: jupyter_client's, less a fixed wait per kernel.

The worker kills each notebook's kernel once its last cell has run (``Execute.shutdown_kernel =
"immediate"``). jupyter_client then polls every 0.1 s until the kernel's process is gone, so a
kernel that dies at once still costs up to 0.1 s, once per notebook of each student. :class:`GradingKernelManager`
polls every 10 ms; everything else is ``AsyncKernelManager``'s. Measured through the kernel factory
(benchmarks/grading_wallclock.txt): a kill took 0.113 s and now 0.024 s.
"""

from __future__ import annotations

from jupyter_client import AsyncKernelManager

DEATH_POLL_S = 0.01


class GradingKernelManager(AsyncKernelManager):
    async def _async_wait(self, pollinterval: float = 0.1) -> None:
        await super()._async_wait(pollinterval=min(pollinterval, DEATH_POLL_S))
