"""What water does to a body: the force terms, hydrostatics, BEM coefficients (Capytaine), the radiation memory and its fit, diffraction, drift, the floating equilibrium."""
