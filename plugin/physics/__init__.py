"""The physics: pure array functions, from the formulas up to the partition of a frame's contacts.

Layers, each importing only those below it:

``formulas``
    the pure formulas numpy and the compiled loops share (a leaf);
``moduli``, ``elastic``
    E*, G*, R*, m* and the energies of Hertz contacts and springs;
``shares``, ``modes``
    the distribution rules and the energy modes, each with its rule;
``laws``
    the contact-law registry, one file per law;
``bodies``
    the two bodies of every contact (materials per pair of types) and the rows a law sees;
``partition``
    energies by law, shares by mode, contact points, sums per body.
"""
