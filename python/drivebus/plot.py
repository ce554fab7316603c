"""Plots of an object over simulated time (matplotlib, optional)."""

from typing import Any, Optional, Union

from ._drivebus import Master, Simulation

__all__ = ["plot"]


def plot(
    sim: Union[Simulation, Master],
    node: int,
    index: Union[int, str],
    sub: Optional[Union[int, str]] = None,
    *,
    seconds: float = 1.0,
    period: float = 0.01,
    ax: Any = None,
    label: Optional[str] = None,
) -> Any:
    """Reads ``index``/``sub`` of ``node`` every ``period`` seconds for ``seconds`` of simulated time
    (``Master.sample``) and plots it against simulated time.

    ``sim`` is a ``Simulation`` or its ``master()``; ``index`` as
    ``sdo_read`` takes it (``0x6064``, ``"position actual value"``). Draws
    on ``ax`` (default: a new figure's axes) and returns the axes.

    :raises ImportError: matplotlib is not installed (``pip install matplotlib``).
    """
    try:
        import matplotlib.pyplot as plt
    except ImportError as e:
        raise ImportError(f"drivebus.plot needs matplotlib ({e}): pip install matplotlib") from e
    master = sim.master() if isinstance(sim, Simulation) else sim
    times, values = master.sample(node, index, sub, seconds=seconds, period=period)
    if ax is None:
        _, ax = plt.subplots()
    what = str(index) if sub is None else f"{index}:{sub}"
    ax.plot(times, values, label=label or f"node {node} {what}")
    ax.set_xlabel("simulated time (s)")
    ax.set_ylabel(what)
    return ax
