"""The texture task and bbob-largescale at 768 to 49,152 parameters: docs/results/large-scale.md."""
