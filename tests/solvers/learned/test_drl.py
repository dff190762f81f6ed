"""The paper's Seq2Seq policy: feasible decoding, masking, forced scoring, and its options."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from gtsp_bench.solvers.learned.checkpoint import save_policy  # noqa: E402
from gtsp_bench.solvers.learned.drl import PointerPolicy  # noqa: E402
from gtsp_bench.solvers.learned.env import make_env  # noqa: E402

from gtsp_bench.errors import InputError  # noqa: E402
from gtsp_bench.generator import generate_batch  # noqa: E402


@pytest.mark.parametrize("options", [{"glimpse": "all"}, {"glimpse": "unvisited"},
                                     {"glimpse": "unvisited", "local": True, "damp": 2},
                                     {"glimpse": "unvisited", "local": True, "energy": True}])
@pytest.mark.parametrize("k", [1, 3, 6, 9])
def test_decoded_orders_are_permutations(k, options):
    """Greedy and sampled orders visit every cluster exactly once; log-probabilities are finite."""
    torch.manual_seed(0)
    model = PointerPolicy(n_nodes=4, dim=16, **options)
    env = make_env(generate_batch(np.random.default_rng(k), 32, k, 4),
                   np.linspace(0, 1, 32))
    gen = torch.Generator().manual_seed(0)
    for mode in ("greedy", "sample"):
        order, logp = model.decode(env, mode, generator=gen)
        assert order.shape == (32, k)
        assert torch.equal(order.sort(1).values, torch.arange(k).expand(32, k))
        assert torch.isfinite(logp).all() and (logp <= 1e-6).all()


@pytest.mark.parametrize("options", [{}, {"glimpse": "unvisited", "local": True, "energy": True}])
def test_forced_decoding_scores_the_given_order(options):
    """decode(forced=order) returns that order and the log-probability sampling gave it; over
    all orders of K = 3 the probabilities sum to 1, and so do those of the 3 one-step prefixes,
    each the sum of its tours'."""
    torch.manual_seed(0)
    model = PointerPolicy(n_nodes=4, dim=16, **options)
    env = make_env(generate_batch(np.random.default_rng(5), 16, 3, 4), np.linspace(0, 1, 16))
    with torch.no_grad():
        order, logp = model.decode(env, "sample", generator=torch.Generator().manual_seed(1))
        again, logp_again = model.decode(env, forced=order)
        assert torch.equal(again, order)
        torch.testing.assert_close(logp_again, logp)
        perms = list(itertools.permutations(range(3)))
        prob = {p: model.decode(env, forced=torch.tensor([p] * 16))[1].exp() for p in perms}
        first = {}
        for j in range(3):
            head, lp = model.decode(env, forced=torch.full((16, 1), j))
            assert head.shape == (16, 1)
            first[j] = lp.exp()
            torch.testing.assert_close(first[j], sum(v for p, v in prob.items() if p[0] == j))
        # decode_first gives every first step's log-probability, as the one-step prefixes do,
        # and decodes what decode does
        o2, l2, lp_first = model.decode_first(env, "sample", generator=torch.Generator().manual_seed(1))
        assert torch.equal(o2, order) and torch.equal(l2, logp)
        torch.testing.assert_close(lp_first.exp(), torch.stack([first[j] for j in range(3)], 1))
    torch.testing.assert_close(sum(prob.values()), torch.ones(16))
    torch.testing.assert_close(sum(first.values()), torch.ones(16))


def test_masking_gives_visited_clusters_zero_probability():
    """Sampling many times from a high-entropy policy never revisits a cluster or the depot."""
    torch.manual_seed(0)
    model = PointerPolicy(n_nodes=3, dim=8)
    with torch.no_grad():
        for p in model.parameters():
            p.mul_(0.01)  # nearly uniform logits: masking alone must prevent repeats
    env = make_env(generate_batch(np.random.default_rng(0), 512, 5, 3), 0.5)
    order, _ = model.decode(env, "sample", generator=torch.Generator().manual_seed(3))
    assert all(len(set(row)) == 5 for row in order.tolist())
    assert order.min() >= 0


def test_unvisited_glimpse_gives_visited_elements_zero_weight():
    """glimpse=unvisited: visited elements (the depot included) get weight 0 and the weights of
    the others sum to 1; glimpse=all weighs every element."""
    env = make_env(generate_batch(np.random.default_rng(4), 16, 6, 4), 0.5)
    visited = torch.zeros((16, 7), dtype=torch.bool)
    visited[:, 0] = True
    visited[torch.arange(16), torch.randint(1, 7, (16,))] = True
    for glimpse in ("unvisited", "all"):
        torch.manual_seed(2)
        model = PointerPolicy(n_nodes=4, dim=16, glimpse=glimpse)
        e = model.embed(env)
        _, a = model.glimpse(e, model.w1(e), torch.randn(16, 16), visited)
        assert torch.allclose(a.sum(1), torch.ones(16))
        if glimpse == "unvisited":
            assert (a[visited] == 0).all() and (a[~visited] > 0).all()
        else:
            assert (a > 0).all()


def test_glimpse_option_is_saved_and_checked(tmp_path):
    """The glimpse setting round-trips through a policy file; a bad one is a clear InputError."""
    from gtsp_bench.solvers.learned.checkpoint import load_policy

    path = tmp_path / "g.pt"
    save_policy(PointerPolicy(n_nodes=3, dim=8, glimpse="unvisited"), path)
    assert load_policy(path, "drl").mask_glimpse
    save_policy(PointerPolicy(n_nodes=3, dim=8), path)  # files without the key: glimpse over all
    assert "glimpse" not in load_policy(path, "drl").config
    assert not load_policy(path, "drl").mask_glimpse
    with pytest.raises(InputError, match="glimpse must be one of 'all', 'unvisited'"):
        PointerPolicy(n_nodes=3, dim=8, glimpse="some")


def test_local_term_reads_the_uav_location_of_the_paper_rule():
    """local=True adds f(d(UAV, centroid), d(centroid, depot), omega) to the logits: with f's
    output layer zero it decodes as the model without it; otherwise the probabilities change, and
    the distances it is fed are those from the heads the paper's rule picks along the decoded
    order (the depot first), recorded through a hook."""
    from gtsp_bench.solvers.learned.env import AREA_SCALE, paper_heads

    b, k = 64, 6
    env = make_env(generate_batch(np.random.default_rng(7), b, k, 5), np.linspace(0, 1, b))
    torch.manual_seed(3)
    plain = PointerPolicy(n_nodes=5, dim=16, glimpse="unvisited")
    local = PointerPolicy(n_nodes=5, dim=16, glimpse="unvisited", local=True)
    extra = {f"local.{n}": v for n, v in local.local.state_dict().items()}
    local.load_state_dict({**plain.state_dict(), **extra})
    with torch.no_grad():
        local.local[2].weight.zero_()
        local.local[2].bias.zero_()
        assert all(torch.allclose(a.float(), c.float())
                   for a, c in zip(plain.decode(env), local.decode(env), strict=True))
        local.local[2].weight.normal_(0, 5.0)
        seen = []
        local.local.register_forward_hook(lambda m, args, out: seen.append(args[0]))
        order, logp = local.decode(env)
        assert not torch.allclose(logp, plain.decode(env)[1])
    feats = torch.stack(seen[:k], 1)  # (B, step, K + 1, 3)
    heads = paper_heads(env, order)
    rows = torch.arange(b)[:, None]
    xy = env.coords[rows, order, heads[rows, order]]  # the heads in visiting order
    where = torch.cat([env.depot[:, None], xy[:, :-1]], 1) / AREA_SCALE  # before each step
    pts = torch.cat([env.depot[:, None], env.coords.mean(2)], 1) / AREA_SCALE
    near = (pts[:, None] - where[:, :, None]).pow(2).sum(-1).sqrt()
    home = (pts - pts[:, :1]).pow(2).sum(-1).sqrt()
    assert torch.allclose(feats[..., 0], near.float(), atol=1e-6)
    assert torch.allclose(feats[..., 1], home[:, None].expand(b, k, k + 1).float(), atol=1e-6)
    assert torch.allclose(feats[..., 2], env.omega[:, None, None].expand(b, k, k + 1).float())


def test_local_option_is_saved_and_checked(tmp_path):
    """The local setting round-trips through a policy file; a non-bool is a clear InputError."""
    from gtsp_bench.solvers.learned.checkpoint import load_policy

    path = tmp_path / "l.pt"
    policy = PointerPolicy(n_nodes=3, dim=8, local=True)
    save_policy(policy, path)
    loaded = load_policy(path, "drl")
    assert loaded.config["local"] is True
    assert all(torch.equal(a, b) for a, b in zip(policy.state_dict().values(),
                                                 loaded.state_dict().values(), strict=True))
    save_policy(PointerPolicy(n_nodes=3, dim=8), path)
    assert "local" not in load_policy(path, "drl").config
    with pytest.raises(InputError, match="local must be true or false"):
        PointerPolicy(n_nodes=3, dim=8, local="yes")


def test_damp_leaves_the_training_k_alone_and_weights_the_pointer_beyond_it():
    """damp = D scales the pointer's logits by min(1, D / clusters left): up to D clusters the
    policy is exactly the undamped one; with more, the first step's probabilities are those of
    pointer * D / K + local term (checked against a hand computation); damp needs local."""
    from gtsp_bench.solvers.learned.decoding import CLIP

    torch.manual_seed(5)
    plain = PointerPolicy(n_nodes=5, dim=16, glimpse="unvisited", local=True)
    damped = PointerPolicy(n_nodes=5, dim=16, glimpse="unvisited", local=True, damp=4)
    damped.load_state_dict(plain.state_dict())
    small = make_env(generate_batch(np.random.default_rng(1), 32, 4, 5), np.linspace(0, 1, 32))
    big = make_env(generate_batch(np.random.default_rng(2), 32, 8, 5), np.linspace(0, 1, 32))
    with torch.no_grad():
        assert all(torch.equal(a, b) for a, b in zip(plain.decode(small), damped.decode(small),
                                                     strict=True))
        runs = {}
        for name, model in (("plain", plain), ("damped", damped)):
            pointer: list[torch.Tensor] = []
            local: list[torch.Tensor] = []
            hooks = [model.v_g.register_forward_hook(
                         lambda m, args, out, seen=pointer: seen.append(out.squeeze(-1))),
                     model.local.register_forward_hook(
                         lambda m, args, out, seen=local: seen.append(out.squeeze(-1)))]
            order, _ = model.decode(big)
            for hook in hooks:
                hook.remove()
            runs[name] = (pointer[0], local[0], order)
    (p0, l0, plain_order), (p1, l1, damped_order) = runs["plain"], runs["damped"]
    assert torch.equal(p0, p1) and torch.equal(l0, l1)  # the same inputs to the first choice
    assert torch.equal(plain_order[:, 0], (CLIP * torch.tanh(p0 + l0))[:, 1:].argmax(1))
    assert torch.equal(damped_order[:, 0], (CLIP * torch.tanh(p0 * 4 / 8 + l0))[:, 1:].argmax(1))
    assert not torch.equal(plain_order, damped_order)
    with pytest.raises(InputError, match="damp needs the local term"):
        PointerPolicy(n_nodes=3, dim=8, damp=4)
    with pytest.raises(InputError, match="damp must be an integer"):
        PointerPolicy(n_nodes=3, dim=8, local=True, damp=-1)


def test_energy_features_are_the_paper_rules_next_step():
    """energy=True feeds, per cluster, the energy the paper's rule pays to enter it from the UAV's
    location (kJ) and the distance from the head it picks to the depot: the same as one step of
    paper_head_step, priced by hand; the depot's column is 0; energy needs local."""
    from gtsp_bench.solvers.learned.env import AREA_SCALE, paper_head_step

    b, k = 16, 5
    env = make_env(generate_batch(np.random.default_rng(1), b, k, 6), np.linspace(0, 1, b))
    where = env.coords[:, 2, 3]  # hovering above node 3 of cluster 2
    enter, back = PointerPolicy._rule_features(env, where)
    assert enter.shape == back.shape == (b, k + 1)
    assert (enter[:, 0] == 0).all() and (back[:, 0] == 0).all()
    rows = torch.arange(b)
    for c in range(k):
        j, xy = paper_head_step(env, where, torch.full((b,), c))
        cost = env.edge_per_m * (xy - where).pow(2).sum(-1).sqrt() + env.node_cost[rows, c, j]
        assert torch.allclose(enter[:, c + 1] * 1000, cost)
        assert torch.allclose(back[:, c + 1], (xy - env.depot).pow(2).sum(-1).sqrt() / AREA_SCALE)
    with pytest.raises(InputError, match="energy needs the local term"):
        PointerPolicy(n_nodes=3, dim=8, energy=True)
