"""Contact laws between the rope net and the rigid missile (paper §IV): normal force Eq. (28)–(29)
with a choice of damping model and a bounded approach-speed rule, contact stiffness Eq. (30)–(31)
(crossed cylinders), friction Eq. (32).

``transfer.py`` (contact loads → fin shell mesh) belongs to the shell stage.
"""
