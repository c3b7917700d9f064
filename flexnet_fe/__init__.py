"""flexnet_fe: an airborne flexible net intercepting a missile, from a case file to a stress report.

Stages (each a function of typed inputs, see DESIGN.md §3): deploy → collide → shell → flight.
SI units everywhere inside the package.
"""

__version__ = "0.1.0"
