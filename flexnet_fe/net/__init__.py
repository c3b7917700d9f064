"""Net deployment physics: lumped-mass rope nets (traction and rotary), paper §III, Eq. (1)–(19)."""
