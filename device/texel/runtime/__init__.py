# texel.runtime: the display runtime: boards, scenes, sensor, duty law, refresh.
