"""The Tactile Paintbrush (seed 002, ../shared/seeds/002_*.txt; ../shared/SPEC.md §6;
docs/brush.md): a texture as a "brush" - per wavenumber of a space-frequency
transform of its friction map (1 mm windows every 0.25 mm, geometry in
device/texel/gen/brush.py), the Weibull distribution of the spectral
magnitudes across windows. The analysis side is pure logic (numpy, scipy,
scikit-learn; never the link, a command or a web framework,
docs/architecture.md): `transform` (the windows' magnitudes, recordings and
their resampling to the display's 5.3 um), `fits` (Rayleigh, Rice and
Weibull per wavenumber by maximum likelihood, K-S statistics), `swipes` (the
data we have: reference textures and texel renderings, and noisy fingertip
swipes of them) and `compare` (the paper's comparison: K-S tables,
silhouette scores and MDS per model and distance metric, brush distances).
"""
