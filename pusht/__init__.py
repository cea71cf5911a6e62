"""World Models II: Acting in Imagination - the chapter's helper package.

One module per idea: ``env`` (PushT on pymunk), ``expert``, ``data``, ``world_model``, ``reward``,
``agent``, ``imagination`` (learning inside the frozen dream), ``evaluate`` (the same policy in two
worlds), ``dreamer`` (the pipeline and its command line), ``config``, ``predict``, ``draw``, ``page``,
``record`` (the optional Rerun recording).
"""

__version__ = "0.1.0"
