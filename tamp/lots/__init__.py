"""LTL tasks with local observation: Zhou et al.'s LOTS reactive planner (§III–IV, Alg. 1–3).

Modules (importing this package loads no Spot; each module imports it where it is needed):

- ``task``        task and interference files (YAML, version 1), strictly validated
- ``automaton``   the task's state-based Büchi automaton (from `tamp.ltl`), executable letters,
                  views
- ``lots``        LOTS counts, Lemma 1 (``|S^B| = ∏(n'_i + 1)``)
- ``planner``     initial lasso, Dijkstra/A* on (automaton state, W^B counts) pairs (Alg. 2),
                  the table ``T`` and the tree ``TR`` with its update (Alg. 3)
- ``cell``        the workcell as a `tamp.world.WorldState` (areas A, B, waste; objects with a
                  class), the ``lots_arm`` skills, and `visible_counts` (what the camera sees)
- ``controller``  Alg. 1, tick-based against any `tamp.world.World` (start / poll a skill)
- ``person``      the scripted person: interference events applied to the `SymbolicWorld`
- ``product``     the product-automaton baseline (Lemma 2)
- ``run``         run a task on the `SymbolicWorld` and report (what ``tamp lots`` prints)
"""
