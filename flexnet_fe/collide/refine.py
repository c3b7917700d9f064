"""Rope subdivision near the contact (``[collide] rope_split``, ``rope_split_margin``).

The deployed net's mesh is as coarse as the deploy needs (paper: 0.1 m bars), but the rope–fin
contact resolves a rope only at its nodes' mass: a rope bar draped over a fin is one straight
spring whose two end masses carry the whole bar. The collision headlines depend on that (docs/
collide_convergence.md: radar × traction Δv −35 % from k = 1 to 2). :func:`split_near_path` splits
every rope segment whose two end nodes lie within ``margin`` [m] of the missile's swept volume —
the cylinder of the missile's bounding radius r_max (fins included) around the flight path
through the aim point — into ``k`` equal segments at collision start:

* new nodes on the chord of the held segment (the held net is straight between its nodes), at rest;
  their reference positions ``x0`` likewise on the chord of the model's reference segment;
* each piece keeps E·A (the rope's section); rest length and LINK167 slack offset are divided by
  k, so the chain of k pieces has the segment's rest length, slack and axial stiffness EA/l0;
* the rope mass ρ A l0 of the segment (Eq. (2) lumping, half to each end) is re-lumped: each end
  node keeps 1/(2k) of it, each of the k − 1 new nodes gets 1/k; concentrated masses stay where
  they are. Total mass, centre of mass and (at rest) momentum are unchanged;
* dashpots (Eq. (4)): the rope keeps its material viscosity, i.e. k dashpots in series make the
  segment's dashpot: c_piece = k c_segment — the same rule the net builder uses for
  ``net.subdivisions`` (``net.topology._rope_segments``), so the split converges to the same
  continuum rope as a finer deploy mesh.

Hub links (rotary nets) are not split: their rest length is measured from the hub centre.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from flexnet_fe.collide.crop import free_nodes
from flexnet_fe.collide.scene import HeldNet, missile_attitude, shape_bbox


def near_path_segments(x: np.ndarray, springs: np.ndarray, hub_link: np.ndarray, aim: np.ndarray,
                       direction: np.ndarray, radius: float) -> np.ndarray:
    """Indices (s,) int64 of the segments (springs (m, 2)) whose two end nodes (x [m] (n, 3)) are
    within ``radius`` [m] of the line through ``aim`` [m] (3,) along unit ``direction`` (3,);
    hub links (hub_link (m,) bool) excluded."""
    near = free_nodes(x, aim, direction, radius)
    return np.flatnonzero(near[springs[:, 0]] & near[springs[:, 1]] & ~hub_link)


def _chord_points(xa: np.ndarray, xb: np.ndarray, k: int) -> np.ndarray:
    """The k − 1 interior points dividing each chord a→b (xa, xb [m] (s, 3)) into k equal parts,
    in segment order, shape (s·(k − 1), 3)."""
    frac = (np.arange(1, k) / k)[None, :, None]
    return (xa[:, None, :] + frac * (xb - xa)[:, None, :]).reshape(-1, 3)


def split_segments(net: HeldNet, idx: np.ndarray, k: int) -> HeldNet:
    """``net`` with the segments ``idx`` (s,) int64 each split into ``k`` ≥ 1 equal pieces (module
    docstring: chord nodes, E·A kept, rest length / slack offset / k, mass re-lumped, c × k).
    The new nodes are appended after the old ones (old node ids unchanged); the pieces replace
    their segments at the end of the segment list, in segment order."""
    if k == 1 or idx.size == 0:
        return net
    m = net.model
    a, b = m.springs[idx, 0], m.springs[idx, 1]
    seg_mass = net.rope.density * 0.25 * np.pi * net.rope.diameter ** 2 * m.rest_length[idx]
    mass = np.array(m.mass, dtype=np.float64)
    np.add.at(mass, a, -(0.5 - 0.5 / k) * seg_mass)  # each end keeps 1/(2k) of the segment's rope
    np.add.at(mass, b, -(0.5 - 0.5 / k) * seg_mass)
    n_new = idx.size * (k - 1)
    new_id = m.n_nodes + np.arange(n_new).reshape(idx.size, k - 1)
    chain = np.column_stack([a, new_id, b])  # (s, k + 1) node ids along each split segment
    pieces = np.stack([chain[:, :-1], chain[:, 1:]], axis=-1).reshape(-1, 2)
    keep = np.setdiff1d(np.arange(m.n_springs), idx)

    def per_piece(arr, scale=1.0):
        arr = np.asarray(arr)
        return np.concatenate([arr[keep], np.repeat(arr[idx], k) * scale])

    model = dataclasses.replace(
        m, x0=np.concatenate([m.x0, _chord_points(m.x0[a], m.x0[b], k)]),
        v0=np.concatenate([m.v0, np.zeros((n_new, 3))]),
        mass=np.concatenate([mass, np.repeat(seg_mass / k, k - 1)]),
        springs=np.concatenate([m.springs[keep], pieces]).astype(np.int64),
        rest_length=per_piece(m.rest_length, 1.0 / k), stiffness_ea=per_piece(m.stiffness_ea),
        damping=per_piece(m.damping, float(k)), slack_offset=per_piece(m.slack_offset, 1.0 / k),
        diameter=per_piece(m.diameter), drag_free=np.concatenate([m.drag_free, np.zeros(n_new, dtype=bool)]),
        hub_link=per_piece(m.hub_link), anchor_angle=per_piece(m.anchor_angle))
    return dataclasses.replace(net, model=model, x=np.concatenate([net.x, _chord_points(net.x[a], net.x[b], k)]),
                               rest_length=per_piece(net.rest_length, 1.0 / k))


def split_near_path(net: HeldNet, missile, cfg) -> HeldNet:
    """The held net with every rope segment within ``cfg.rope_split_margin`` [m] of the missile's
    swept volume (bounding radius r_max around the path through ``cfg.aim_point`` along the flight
    direction of ``cfg.incidence_angle``/``roll_angle``) split into ``cfg.rope_split`` pieces
    (:func:`split_segments`; ``rope_split = 1`` returns ``net`` itself)."""
    k = int(cfg.rope_split)
    if k == 1:
        return net
    d = missile_attitude(cfg.incidence_angle, cfg.roll_angle)[:, 0]
    aim = np.array([cfg.aim_point[0], cfg.aim_point[1], 0.0])
    radius = float(shape_bbox(missile)[2]) + cfg.rope_split_margin
    idx = near_path_segments(net.x, net.model.springs, np.asarray(net.model.hub_link, dtype=bool), aim, d, radius)
    return split_segments(net, idx, k)
