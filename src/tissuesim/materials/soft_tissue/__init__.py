"""The soft-tissue laws with FEBio's definitions and names: Mooney-Rivlin, Yeoh,
Veronda-Westmann, Arruda-Boyce and Ogden (uncoupled and coupled forms), one file per family, on
the engine from W(I1, I2, J) to P and dP/dF in ``_hyperelastic.py``."""
