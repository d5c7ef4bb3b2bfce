"""FEBio's history-dependent laws: elastic damage (``damage.py``, its CDFs and criteria in
``damage_functions.py``), reactive visco-elasticity (``reactive_viscoelastic.py``, its
relaxation functions in ``relaxation.py``), the Prony series with damage
(``viscoelastic_damage.py``), solid mixtures whose components keep a history
(``history_mixture.py``)."""
