"""The impact scene (paper §V-C assumptions): a held net and a rigid missile flying into it.

World frame W (``flexnet_fe.frames``): the held net is centred on the origin (the centroid of its
nodes), spread across the x–y plane; the missile flies along
d = (0, −sin i, cos i) (i the incidence angle, pitched about world x; the paper's cases have
i = 0, d = +z) towards the aim point (a_x, a_y, 0). No air acts during the impact (assumption 2)
unless ``[collide] air`` (module ``collide.air``: the rope law in still air); the net is at rest
(assumption 3: "the flexible net is set to static").
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexnet_fe.collide.config import CollideConfig, NetSource
from flexnet_fe.errors import CaseError, FlexnetError
from flexnet_fe.missile.geometry import Missile
from flexnet_fe.missile.shapes import ShapeArrays
from flexnet_fe.net.forces import RopeMaterial
from flexnet_fe.net.topology import NetModel, build_net
from flexnet_fe.frames import quat_from_matrix
from flexnet_fe.runs import NET_STATE


@dataclass(frozen=True)
class HeldNet:
    """The net of the impact (data). model: its ``NetModel`` (topology, masses, springs);
    x [m] (n, 3) held positions in W (velocities are zero); rest_length [m] (m,) rest lengths used
    in the impact (hub links measured from the hub centre, see :func:`held_net`);
    rope: the rope material (capsule radius = rope radius); source: where x came from."""

    model: NetModel
    x: np.ndarray
    rest_length: np.ndarray
    rope: RopeMaterial
    source: NetSource


@dataclass(frozen=True)
class MissileStart:
    """Initial rigid-body state of the missile (data). x_cg [m] (3,) W; v_cg [m/s] (3,) W;
    q (4,) attitude B → W; apex [m] (3,) nose apex in W; direction (3,) unit flight direction;
    bbox (4,) bounding cylinder of the contact shapes in B and body radius: (x_min, x_max, r_max, R) [m]."""

    x_cg: np.ndarray
    v_cg: np.ndarray
    q: np.ndarray
    apex: np.ndarray
    direction: np.ndarray
    bbox: np.ndarray


def held_net(net_cfg, source: NetSource, deploy_dir: Path | None) -> HeldNet:
    """The held net: the deploy stage's ``net_state.npz`` (net at maximum area; its velocities
    are discarded — paper assumption 1, "net-holding stage") or the flat net of the builder at its
    rest lengths (``flat_taut``). Positions are shifted so the node centroid is the origin.

    Rotary hub (departs from the deploy model): during the ~10 ms impact the hub is a point mass
    that does not spin; its links are springs from the hub centre with rest length l0 + r0 (the
    rim anchor rigidly attached). Its links touch the missile as rope capsules; the hub disc's own
    contact is not modelled (the paper's cases aim off the hub).
    """
    model = build_net(net_cfg)
    if source is NetSource.flat_taut:
        x = np.array(model.x0, dtype=np.float64)
    elif source is NetSource.deploy_max_area:
        if deploy_dir is None:
            raise FlexnetError("collide: net_source = 'deploy_max_area' needs the deploy stage's output "
                               "(run the deploy stage first, or set collide.net_source = 'flat_taut')")
        path = Path(deploy_dir) / NET_STATE
        if not path.is_file():
            raise FlexnetError(f"collide: {path} not found (run the deploy stage first)")
        with np.load(path, allow_pickle=False) as z:
            x = np.array(z["x"], dtype=np.float64)
        if x.shape != model.x0.shape:
            raise CaseError(path, "x", f"net state has shape {x.shape}, the [net] table builds "
                                       f"{model.x0.shape}: deploy and collide used different nets")
    else:
        raise ValueError(f"unknown net source {source!r}")
    x -= x.mean(axis=0)
    rest = np.array(model.rest_length, dtype=np.float64)
    if model.hub_node >= 0:
        rest[model.hub_link] += model.hub_radius
    return HeldNet(model, x, rest, model.rope, source)


def shape_bbox(missile: Missile) -> np.ndarray:
    """Bounding cylinder of the contact shapes in B and body radius: (x_min, x_max, r_max, R) [m]."""
    r = missile.radius
    x_lo, x_hi = -missile.length, 0.0
    for fin in missile.fins:
        c = np.asarray(fin.corners)
        r = max(r, float(np.max(np.hypot(c[:, 1], c[:, 2]))) + 0.5 * fin.thickness)
        x_lo = min(x_lo, float(c[:, 0].min()))
        x_hi = max(x_hi, float(c[:, 0].max()))
    return np.array([x_lo, x_hi, r, missile.radius])


def fin_planes(shapes: ShapeArrays) -> np.ndarray:
    """Broad-phase data of the fins for the kernel, (nf, 7): unit normal n (3), n·origin [m],
    x range [m] of the contact plate (root extension included), half-thickness [m], in B."""
    nf = shapes.fin_origin.shape[0]
    out = np.zeros((nf, 7))
    for i in range(nf):
        o, ax, poly = shapes.fin_origin[i], shapes.fin_axes[i], shapes.fin_poly[i]
        corners = o + poly[:, :1] * ax[0] + poly[:, 1:] * ax[1]
        out[i, :3] = ax[2]
        out[i, 3] = float(ax[2] @ o)
        out[i, 4] = float(corners[:, 0].min())
        out[i, 5] = float(corners[:, 0].max())
        out[i, 6] = shapes.fin_half_thickness[i]
    return out


def missile_attitude(incidence: float, roll: float) -> np.ndarray:
    """Rotation matrix R (3, 3), B → W: x_b along d = R_x(i) ẑ, y_b along R_x(i) ŷ before roll;
    then a right-handed roll ``roll`` [rad] about x_b."""
    ci, si = np.cos(incidence), np.sin(incidence)
    xb = np.array([0.0, -si, ci])
    yb = np.array([0.0, ci, si])
    zb = np.cross(xb, yb)
    base = np.column_stack([xb, yb, zb])
    cr, sr = np.cos(roll), np.sin(roll)
    roll_b = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    return base @ roll_b


def place_missile(missile: Missile, net_x: np.ndarray, cfg: CollideConfig) -> MissileStart:
    """Put the nose apex ``cfg.standoff`` before the first net point the missile's shapes would
    reach along its path (through the aim point), flying at ``cfg.impact_speed`` along d."""
    r = missile_attitude(cfg.incidence_angle, cfg.roll_angle)
    d = r[:, 0]
    aim = np.array([cfg.aim_point[0], cfg.aim_point[1], 0.0])
    bbox = shape_bbox(missile)
    rel = net_x - aim
    along = rel @ d
    perp = np.linalg.norm(rel - np.outer(along, d), axis=1)
    ahead = along[perp <= bbox[2]]
    first = float(ahead.min()) if ahead.size else 0.0
    apex = aim + (first - cfg.standoff) * d
    x_cg = apex + r @ np.asarray(missile.cg)
    return MissileStart(x_cg=x_cg, v_cg=cfg.impact_speed * d, q=quat_from_matrix(r), apex=apex,
                        direction=d, bbox=bbox)
