"""The viser web application (scene, plots, operator controls, replay)."""
