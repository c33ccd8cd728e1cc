# texel.hw: hardware backends, one per port; a board's image carries only its own.
