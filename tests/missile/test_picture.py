"""The offscreen missile picture is written (smoke test of the EGL/PyVista path)."""

from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.missile.mesh import write_meshes
from flexnet_fe.missile.picture import render_missile_png


def test_picture_written(tmp_path):
    cfg = MissileConfig(preset="infrared", mesh_size=0.05)
    png = render_missile_png(write_meshes(cfg, tmp_path / "m"), tmp_path / "missile.png",
                             "infrared", window_size=(400, 200))
    import matplotlib.image as mpimg

    img = mpimg.imread(png)
    assert img.shape[:2] == (200, 400)
    # something other than the white background was drawn (the missile covers > 2 % of pixels)
    assert (img[..., :3].min(axis=2) < 0.9).mean() > 0.02
