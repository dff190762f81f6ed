"""Learned policies: the paper's pointer network (drl) and an attention model (am).

Modules, each importing only those above it:

* ``env``: the batch environment (:class:`~.env.EnvBatch`), tour costs, the two head rules
  (``HEAD_RULES``: paper, optimal) and the features a model reads;
* ``oracles``: exact optima on a batch (enumeration; the best order under the paper's rule);
* ``decoding``: one decoding step (clipped logits, masking, greedy / sampled / forced);
* ``drl``, ``am``: the policies (plain ``nn.Module``s);
* ``policies``: the registry of policy classes by name (``POLICIES``, ``get_policy``);
* ``baselines``: the critic and POMO baselines behind one ``Baseline`` protocol;
* ``checkpoint``: policy files (save, ``weights_only`` load) and the shipped ``checkpoints/``;
* ``solver``: the registered solvers ``drl``, ``drl-sample``, ``am``;
* ``recipes``: the named training recipes (``RECIPES``: drl, drl-paper, am; ``get_recipe``);
* ``train``: the training loop.

Importing this package imports only :mod:`pathlib` (not torch): it names the shipped models'
folder, which the runner reads training logs from without loading a policy.
"""

from pathlib import Path

#: Where the shipped checkpoints (``<model>.pt``, ``.json``, ``.train.csv``) live.
CHECKPOINT_DIR = Path(__file__).resolve().parent / "checkpoints"
