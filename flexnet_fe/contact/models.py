"""The closed choices of the contact law, as data (no numba here: the case schema imports it)."""

from __future__ import annotations

from enum import Enum


class DampingModel(str, Enum):
    """Hysteresis damping factor χ of F_n = K δ^m (1 + χ δ̇); v_k is the approach speed at first touch.

    lankarani_nikravesh  χ = 3(1 − e²)/(4 v_k)   (paper Eq. (29) as printed; Lankarani & Nikravesh 1990,
                         derived for e → 1)
    hunt_crossley        χ = 3(1 − e)/(2 v_k)    (Hunt & Crossley 1975, their own relation, e → 1)
    flores               χ = 8(1 − e)/(5 e v_k)  (Flores, Machado, Silva, Martins 2011, valid for all e)
    none                 χ = 0 (purely elastic Hertz contact)
    """

    lankarani_nikravesh = "lankarani_nikravesh"
    hunt_crossley = "hunt_crossley"
    flores = "flores"
    none = "none"


DAMPING_CODE: dict[DampingModel, int] = {
    DampingModel.none: 0,
    DampingModel.lankarani_nikravesh: 1,
    DampingModel.hunt_crossley: 2,
    DampingModel.flores: 3,
}
"""Integer code of each damping model, as the numba kernels take it."""
