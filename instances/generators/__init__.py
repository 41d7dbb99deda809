"""Instance generators (``bille gen``): grid graphs and the paper's reductions, random and
paper-style instances, MovingAI maps. Every generator is seeded and deterministic."""
