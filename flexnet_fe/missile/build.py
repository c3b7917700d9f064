"""The rigid missile of a ``[missile]`` table: geometry (``geometry``) plus mass properties
(``mass``). Here, above both, so that ``mass`` may use the geometry without an import cycle."""

from __future__ import annotations

import numpy as np

from flexnet_fe.missile.config import MassModel, MissileConfig
from flexnet_fe.missile.geometry import Missile, _frozen, body_profile, build_fins
from flexnet_fe.missile.mass import missile_mass_properties


def build_missile(cfg: MissileConfig) -> Missile:
    """The rigid missile of a validated ``[missile]`` table (mass model per ``cfg.mass_model``)."""
    R = 0.5 * cfg.body_diameter
    profile = body_profile(cfg.body_length, R, cfg.nose_shape, cfg.nose_length)
    fins = build_fins(cfg)
    if cfg.mass_model is MassModel.UNIFORM_DENSITY:
        mass, cg, inertia = missile_mass_properties(
            cfg.body_length, R, cfg.nose_shape, cfg.nose_length, cfg.body_density, fins)
    elif cfg.mass_model is MassModel.GIVEN:
        mass, cg, inertia = cfg.mass, np.array(cfg.cg), np.array(cfg.inertia)
    else:
        raise ValueError(f"unknown mass model {cfg.mass_model!r}")
    return Missile(name=cfg.name, length=cfg.body_length, radius=R, nose_shape=cfg.nose_shape,
                   nose_length=cfg.nose_length, profile=profile, fins=fins, mass=float(mass),
                   cg=_frozen(cg), inertia=_frozen(inertia))
