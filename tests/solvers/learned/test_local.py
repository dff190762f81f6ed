"""The local-view policy: K-free views, the symmetry its starts rely on, feasible decoding."""

from __future__ import annotations

import math

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from gtsp_bench.solvers.learned.env import env_from_instances  # noqa: E402
from gtsp_bench.solvers.learned.local import (  # noqa: E402
    EXCESS_CLIP,
    LocalPolicy,
    Walk,
    _flight_per_m,
    encoder_layer,
    frame,
    turn,
)

from gtsp_bench.generator import instance_set  # noqa: E402
from gtsp_bench.instance import Instance  # noqa: E402


def _env(k: int, n: int = 2, omega: float = 0.3, area: float = 1000.0):
    insts = instance_set(n, k, 4_242, 6, area=area)
    return env_from_instances(insts, [omega] * n), insts


def _rotated(inst: Instance, angle: float) -> Instance:
    """The instance turned by ``angle`` about its depot (every cost unchanged)."""
    c, s = math.cos(angle), math.sin(angle)
    rot = np.array([[c, -s], [s, c]])
    dep = np.asarray(inst.depot)
    clusters = tuple((xy - dep) @ rot.T + dep for xy in inst.clusters)
    return Instance(inst.name, clusters, inst.depot, inst.params)


def test_view_shapes_padding_and_ranges():
    """Fewer clusters than candidates: the view is padded and masked; the features stay in range,
    and candidates are the nearest unvisited clusters (by centroid), nearest first."""
    env, _ = _env(5)
    walk = Walk(env, 3, 8, _flight_per_m(env))
    v = walk.view()
    assert v.cand_vec.shape == (6, 8, 2, 2) and v.mask.shape == (6, 8)
    assert v.mask.sum(1).tolist() == [5] * 6
    assert float(v.cand_vec[~v.mask].abs().sum()) == 0.0
    # the farthest candidate's centroid is at distance 1 (the local scale)
    far = v.cand_vec[:, :, 1].norm(dim=-1).masked_fill(~v.mask, 0).max(1).values
    assert torch.allclose(far, torch.ones(6), atol=1e-5)
    assert (v.cand_sc[..., 0] >= 0).all() and (v.cand_sc[..., 0] <= EXCESS_CLIP).all()
    walk.move(v, torch.zeros(6, dtype=torch.long))
    v2 = walk.view()
    assert v2.mask.sum(1).tolist() == [4] * 6
    assert not (v2.cluster[v2.mask] == v.cluster[:, :1].expand(-1, 8)[v2.mask]).any()
    assert torch.allclose(v2.ctx_sc[:, 1], torch.full((6,), 4 / 5))


def test_view_is_invariant_under_rotation():
    """Turning the instance about the depot turns the view's vectors and leaves its scalars: the
    symmetry behind the rotated starts."""
    env, insts = _env(12, n=1)
    angle = 0.7
    env_r = env_from_instances([_rotated(insts[0], angle)], [0.3])
    v = Walk(env, 1, 6, _flight_per_m(env)).view()
    vr = Walk(env_r, 1, 6, _flight_per_m(env_r)).view()
    assert torch.equal(v.cluster, vr.cluster)
    maps = torch.tensor([[[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]]],
                        dtype=torch.float32)
    turned = turn(v, maps)
    assert torch.allclose(turned[0], vr.cand_vec, atol=1e-4)
    assert torch.allclose(turned[2], vr.ctx_vec, atol=1e-4)
    assert torch.allclose(v.cand_sc, vr.cand_sc, atol=1e-4)
    assert torch.allclose(v.ctx_sc, vr.ctx_sc, atol=1e-4)


def test_frame_is_orthogonal_and_distinct():
    maps = frame(8)
    eye = torch.eye(2).expand(8, 2, 2)
    assert torch.allclose(maps @ maps.transpose(1, 2), eye, atol=1e-6)
    dets = torch.linalg.det(maps)
    assert torch.allclose(dets, torch.tensor([1.0, -1.0] * 4), atol=1e-6)
    assert len({tuple(m.flatten().round(decimals=4).tolist()) for m in maps}) == 8


def test_decoding_is_feasible_at_k200():
    """Greedy and sampled tours of an untrained policy visit each of 200 clusters once."""
    torch.manual_seed(0)
    env, _ = _env(200, n=1, area=3000.0)
    model = LocalPolicy(dim=16, n_heads=2, n_layers=1, ff=32, k=8).eval()
    with torch.inference_mode():
        order, logp = model.decode(env, starts=2)
        sampled, _ = model.decode(env, "sample", starts=1, generator=torch.Generator().manual_seed(1))
    assert order.shape == (2, 200) and torch.isfinite(logp).all()
    for row in (*order, *sampled):
        assert sorted(row.tolist()) == list(range(200))


def test_scores_mask_missing_candidates():
    model = LocalPolicy(dim=16, n_heads=2, n_layers=1, ff=32, k=4)
    mask = torch.tensor([[True, True, False, False]])
    logits = model.scores(torch.randn(1, 4, 2, 2), torch.randn(1, 4, 2), torch.randn(1, 2, 2),
                          torch.randn(1, 3), mask)
    assert torch.isinf(logits[0, 2:]).all() and torch.isfinite(logits[0, :2]).all()


def test_shrunk_view_scores_as_the_padded_one():
    """With fewer clusters left than candidates, a shrunk view (as decoding uses) has only the
    clusters left, and the policy scores them as in the padded view (padding is masked out of the
    attention), with or without missing candidates in some rows."""
    torch.manual_seed(0)
    env, _ = _env(12, n=2)
    model = LocalPolicy(dim=16, n_heads=2, n_layers=2, ff=32, k=8).eval()
    walks = [Walk(env, 2, 8, _flight_per_m(env), shrink=s) for s in (False, True)]
    for w in walks:  # rows 0-1 visit 7 clusters, rows 2-3 visit 8
        visited = torch.zeros((4, 12), dtype=torch.bool)
        visited[:2, :7] = True
        visited[2:, :8] = True
        w.visited = visited
    padded, shrunk = (w.view() for w in walks)
    assert padded.mask.shape == (4, 8) and shrunk.mask.shape == (4, 5)
    assert torch.equal(padded.cluster[:, :5][shrunk.mask], shrunk.cluster[shrunk.mask])
    with torch.inference_mode():
        a = model.scores(*turn(padded, frame(4)), padded.mask)
        b = model.scores(*turn(shrunk, frame(4)), shrunk.mask)
    assert torch.isinf(a[:, 5:]).all()
    assert torch.allclose(a[:, :5][shrunk.mask], b[shrunk.mask], atol=1e-5)
    assert torch.isinf(b[~shrunk.mask]).all()


def test_decoding_with_shrunk_views_matches_padded_views():
    """Greedy decoding (shrunk views) gives the tours that padded views give."""
    torch.manual_seed(1)
    env, _ = _env(10, n=3)
    model = LocalPolicy(dim=16, n_heads=2, n_layers=2, ff=32, k=16).eval()
    with torch.inference_mode():
        order, _ = model.decode(env, starts=2)
        walk = Walk(env, 2, 16, _flight_per_m(env))
        maps = frame(2).repeat(3, 1, 1)
        steps = []
        for _ in range(10):
            v = walk.view()
            steps.append(walk.move(v, model.scores(*turn(v, maps), v.mask).argmax(-1)))
    assert torch.equal(order, torch.stack(steps, 1))


@pytest.mark.parametrize("padded", [False, True])
def test_encoder_layer_is_the_modules_layer(padded):
    """Decoding's plain-operation layer gives the module's outputs (every unpadded token), and
    scores with and without gradients agree (training runs the module, decoding the function)."""
    torch.manual_seed(2)
    model = LocalPolicy(dim=32, n_heads=4, n_layers=2, ff=48, k=6).eval()
    layer = model.encoder.layers[0]
    x = torch.randn(5, 7, 32)
    pad = None
    if padded:
        pad = torch.zeros(5, 7, dtype=torch.bool)
        pad[1, 4:] = True
        pad[3, 6] = True
    with torch.inference_mode():
        ours = encoder_layer(layer, x, pad)
        theirs = layer(x, src_key_padding_mask=pad)
    keep = torch.ones(5, 7, dtype=torch.bool) if pad is None else ~pad
    assert torch.allclose(ours[keep], theirs[keep], atol=1e-5)
    mask = torch.ones(5, 6, dtype=torch.bool) if pad is None else ~pad[:, 1:]
    args = (torch.randn(5, 6, 2, 2), torch.randn(5, 6, 2), torch.randn(5, 2, 2), torch.randn(5, 3))
    with torch.inference_mode():
        fast = model.scores(*args, mask)
    slow = model.scores(*args, mask)
    assert slow.requires_grad
    assert torch.allclose(fast[mask], slow.detach()[mask], atol=1e-5)
    assert torch.isinf(fast[~mask]).all()
