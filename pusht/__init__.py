"""World Models II: Acting in Imagination - the chapter's helper package.

One module per idea. The world: ``env`` (PushT on pymunk), ``expert``, ``data``. The learning:
``world_model``, ``reward``, ``agent``, ``imagination`` (learning inside the frozen dream), ``optim``.
The two stages and their cache: ``wm_stage``, ``agent_stage``, ``stage_cache``. The measuring:
``evaluate`` (the same policy in two worlds), ``split`` (the gap taken apart), ``analysis``
(distribution shift), ``metric_keys`` (where each metric's key is born), ``gate`` (can the dream be
trusted to act in?). Acting without an actor: ``plan`` (CEM in the frozen model). The conductors:
``dreamer`` (the pipeline), ``loop`` (the real-data loop),
``sweep`` (runs side by side), ``cli``. The rest: ``config``, ``predict``, ``exercise``,
``selfcheck``, ``draw``, ``record`` (the optional Rerun recording), ``page``, ``host``, ``fingerprint``,
``runtime``; ``reference`` and ``grading`` (what the learner shares with the grader); ``nb`` (the
notebooks' rooms). ``grader`` is the grader's runtime, which a learner never imports.
"""

__version__ = "0.1.0"
