"""bifilar: plan, simulate and invert bifilar / multifilar pendulum experiments.

Data flow: config -> scene (body + rig) -> models -> analysis (equilibrium,
modes, simulation) -> estimation -> studies -> cli.  SI units throughout.
"""

__version__ = "0.1.0"
