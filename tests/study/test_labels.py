"""Point labels of the study charts (``study.plots.label_offsets``): placed without overlaps."""
import numpy as np

from flexnet_fe.study.plots import _boxes_overlap, label_offsets


def _boxes(anchors, widths, height, offsets):
    return [(x + dx, y + dy, x + dx + w, y + dy + height) for (x, y), w, (dx, dy, _) in zip(anchors, widths, offsets)]


def test_crowded_labels_do_not_overlap_each_other_or_the_points_and_stay_in_the_frame():
    # Reference: plane geometry. Six points within 3 pt of each other (the shell chart's cluster at the
    # default) in a 400 × 300 pt frame: the rings offer 32 positions, so every label finds a box that
    # overlaps no other label and no point's 6 pt disc, inside the frame; those past the first ring get
    # a leader line.
    anchors = np.array([[200.0, 150.0], [201.0, 151.0], [202.0, 149.0], [199.0, 150.0], [203.0, 152.0],
                        [200.0, 148.0]])
    widths = np.full(6, 60.0)
    frame = (0.0, 0.0, 400.0, 300.0)
    offsets = label_offsets(anchors, widths, 8.4, frame)
    boxes = _boxes(anchors, widths, 8.4, offsets)
    for i, a in enumerate(boxes):
        assert frame[0] <= a[0] and frame[1] <= a[1] and a[2] <= frame[2] and a[3] <= frame[3]
        assert not any(_boxes_overlap(a, b) for b in boxes[i + 1:])
        assert not any(_boxes_overlap(a, (x - 6, y - 6, x + 6, y + 6)) for x, y in anchors)
    assert any(leader for *_, leader in offsets)  # six labels cannot all sit next to their points


def test_a_point_near_the_frame_edge_gets_its_label_inside():
    # Reference: plane geometry; the first candidate (up and right) would leave the frame.
    offsets = label_offsets(np.array([[395.0, 295.0]]), np.array([50.0]), 8.4, (0.0, 0.0, 400.0, 300.0))
    (dx, dy, _), = offsets
    assert 395.0 + dx >= 0.0 and 395.0 + dx + 50.0 <= 400.0 and 295.0 + dy + 8.4 <= 300.0
