"""The full shell study's scene: the default impact's fin loads as the case ships them."""

from __future__ import annotations

from flexnet_fe.study.collide import SHIPPED
from flexnet_fe.study.scenes import CASE, FULL_COLLIDE, case_with


def test_the_shell_study_loads_are_sampled_as_the_case_ships_them():
    # Reference: the case file's own collide.load_interval. The collide study's points sample the fin
    # loads at the output interval (scenes.LOADS_AT_OUTPUT, 10 µs); fed to the shell, those loads
    # low-pass the rope's 1–4 µs strikes and the peak read 26 MPa against 78 MPa as shipped on
    # wing_3 at 1.25 mm (docs/study/PROVENANCE.md, twenty-ninth session). The shell study's impact must
    # keep every sampling setting of the case.
    shipped, case = case_with(CASE, SHIPPED).collide, case_with(CASE, ()).collide
    assert shipped.load_interval == case.load_interval is not None
    assert shipped.model_copy(update={"snapshots": case.snapshots}) == case
    assert case_with(CASE, FULL_COLLIDE).collide.load_interval != case.load_interval  # the study's points differ
