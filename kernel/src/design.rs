//! A design (surface, icons, material) as a value: edit, solve, snapshot, restore.
