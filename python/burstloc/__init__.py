"""burstloc: real-time pipe-burst localization in water distribution networks."""
