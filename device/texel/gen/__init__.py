# texel.gen: the generator: parameters, RNG, plan, engines, reference textures.
