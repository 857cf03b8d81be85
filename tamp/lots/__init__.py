"""LTL tasks with local observation: Zhou et al.'s LOTS reactive planner (§III–IV, Alg. 1–3).

Modules (importing this package loads no Spot; each module imports it where it is needed):

- ``task``        task and interference files (YAML, version 1), strictly validated
- ``automaton``   the task's state-based Büchi automaton (from `tamp.ltl`), executable letters,
                  views
- ``lots``        LOTS counts, Lemma 1 (``|S^B| = ∏(n'_i + 1)``)
- ``planner``     initial lasso, Dijkstra/A* on (automaton state, W^B counts) pairs (Alg. 2),
                  the table ``T`` and the tree ``TR`` with its update (Alg. 3)
- ``controller``  Alg. 1 against any `world.LocalWorld`
- ``world``       the `LocalWorld` protocol and the symbolic world with human interference
- ``product``     the product-automaton baseline (Lemma 2)
- ``run``         run a task and report (what ``tamp lots`` prints)
"""
