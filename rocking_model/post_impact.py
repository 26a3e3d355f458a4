"""Closed-form impact of the flexible rocking oscillator: moved to `rocking_model.models.flexible_impact`
(next to the model it belongs to); this name stays for existing scripts."""
from .models.flexible_impact import (ImpactResult, Outcome, analytical_impact, classical_impact,  # noqa: F401
                                     classify_post_impact, impact_delassus)
