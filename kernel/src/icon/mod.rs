//! Icon entities: constraints and loads attached to a surface or curve.
