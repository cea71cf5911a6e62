"""The kernel manager the grading worker gives nbgrader (autograde/kernels.py): jupyter_client's, on a
real kernel, with only the wait for a killed kernel's end shortened."""

import asyncio
from pathlib import Path

import pytest
from jupyter_client import AsyncKernelManager

from autograde.kernels import DEATH_POLL_S, GradingKernelManager

pytestmark = pytest.mark.slow          # starts real kernels


def test_a_killed_kernel_is_gone_and_cleaned_up_as_with_jupyter_clients_manager():
    async def run():
        km = GradingKernelManager(kernel_name="python3")
        await km.start_kernel()
        kc = km.client()
        kc.start_channels()
        await kc.wait_for_ready(timeout=60)
        reply = await kc.execute_interactive("x = 6 * 7", timeout=30)
        assert reply["content"]["status"] == "ok"
        pid = km.provisioner.process.pid
        kc.stop_channels()
        await km.shutdown_kernel(now=True)
        return km, pid

    km, pid = asyncio.run(run())
    assert isinstance(km, AsyncKernelManager) and not km.has_kernel
    assert not Path(f"/proc/{pid}").exists() or "zombie" in Path(f"/proc/{pid}/status").read_text()


def test_the_poll_is_only_ever_shortened():
    seen = []

    class Probe(GradingKernelManager):
        async def _async_is_alive(self):
            return False

    async def spy(self, pollinterval=0.1):
        seen.append(pollinterval)

    original = AsyncKernelManager._async_wait
    AsyncKernelManager._async_wait = spy
    try:
        asyncio.run(Probe()._async_wait())
        asyncio.run(Probe()._async_wait(pollinterval=0.001))
    finally:
        AsyncKernelManager._async_wait = original
    assert seen == [DEATH_POLL_S, 0.001]
