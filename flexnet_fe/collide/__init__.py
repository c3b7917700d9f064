"""The collide stage: deployed net (held) vs rigid 6-DOF missile with continuous contact forces
(paper §IV, §V-C). ``run_collide`` in ``stage.py`` is the entry point."""
