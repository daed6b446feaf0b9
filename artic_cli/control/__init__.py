"""Control: EP maps, dynamic maps and the target solver."""
