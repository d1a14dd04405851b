//! Generators for the bundled sample scenes.
