"""The fibre-reinforced laws (FEBio's names): Holzapfel-Gasser-Ogden and transversely isotropic
Mooney-Rivlin, on ``_fibres.py`` (W(I1, I2, I4_a, J), fibre directions per body, element or
point)."""
