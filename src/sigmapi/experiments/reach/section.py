"""The reach experiment as a section of the reproduction report (``sigmapi reproduce``):
:func:`reach_section` runs :data:`~sigmapi.experiments.reach.run.REACH` (the 2-D task, a
saccade on every step, the same actor-critic on four state representations; ``--quick``: 1
seed of 150 episodes on the 7x7 map of :data:`~sigmapi.experiments.reach.config.SMALL_PRESET`,
else the defaults on the default seeds, the acceptance run), draws the figure and returns the
section.
"""

from __future__ import annotations

import html
from typing import cast

from sigmapi._outputs import save_figure
from sigmapi.executor import Executor
from sigmapi.experiments.kit.report import ReportContext, Section
from sigmapi.experiments.reach.config import ReachConfig
from sigmapi.experiments.reach.result import ReachResult
from sigmapi.experiments.reach.run import REACH
from sigmapi.progress import Progress

FIGURE = "reach-2d.png"
CAPTION = (
    "Success rate and steps to reach per block of episodes for each state, and the learned "
    "value over z."
)

EXPLANATION = {
    "map": (
        "the learned Sigma-Pi map's response (learned, without z, from the view pairs of the "
        "eye's own saccades)"
    ),
    "retina": "the retinal code x alone: under saccades it says little about z",
    "retina_gaze": (
        "x and y side by side: a linear learner can add a function of x to a function of y "
        "but cannot form their conjunction, which the value of the goal needs"
    ),
    "true_z": "a population code of the true body-centred z (the upper bound)",
}


def reach_section(ctx: ReportContext) -> Section:
    """Run the reach comparison (smaller with ``ctx.quick``) and return its report section."""
    cfg = REACH.quick if ctx.quick and REACH.quick is not None else ReachConfig()
    seeds = REACH.default_seeds(cfg, quick=ctx.quick)
    executor = Executor(workers=ctx.options.workers)
    show = Progress(disable=not ctx.progress or None)
    result = cast(ReachResult, REACH.run(cfg, seeds=seeds, executor=executor, progress=show))
    with ctx.drawing:  # the report may be drawing its own figures in another thread
        save_figure(result.draw(), ctx.out / FIGURE, **result.SAVE)

    final = result.final_success()
    per_seed = result.final()
    rows = "".join(
        f"<tr><td>{html.escape(state)}</td><td>{final[state]:.3f}</td>"
        f"<td>{html.escape(' '.join(f'{v:.3f}' for v in per_seed[state]))}</td>"
        f"<td>{html.escape(EXPLANATION.get(state, ''))}</td></tr>"
        for state in final
    )
    ratio = final["map"] / final["true_z"] if final.get("true_z") else float("nan")
    env, agent, run = cfg.env, cfg.agent, cfg.run
    body = (
        f"<p>The 2-D gaze-and-reach task (<code>sigmapi/GazeReach-v0</code>), a saccade with "
        f"probability {env.saccade_rate:g} per step, {env.grid}x{env.grid} retina and gaze "
        f"codes, a {'x'.join(map(str, cfg.map.map_shape))} Sigma-Pi map learned from "
        f"{cfg.map.iterations:,} saccade view pairs per seed; the same actor-critic (discount "
        f"{agent.gamma}, rates {agent.critic_lr}/{agent.actor_lr}, inverse temperature "
        f"{agent.beta}) on each state, {run.episodes} episodes x {len(seeds)} seeds. Final "
        f"success = rate over the last {run.final_episodes} episodes. Map / true z = "
        f"{ratio:.3f} (target: at least 0.95).</p>"
        "<table><tr><th>state</th><th>final success (mean)</th><th>per seed</th>"
        f"<th>what the learner sees</th></tr>{rows}</table>"
    )
    return Section(
        title="From map to action: learning to reach",
        html=body,
        figures=[(FIGURE, CAPTION)],
        data={
            "config": {"episodes": run.episodes, "seeds": len(seeds), "quick": ctx.quick},
            "success": final,
            "success_per_seed": {k: [float(x) for x in v] for k, v in per_seed.items()},
            "map_over_true_z": ratio,
        },
    )
