"""Generated scenes, apart from the model: the demo brake (`demo`), random and Table 1
assemblies (`generate`), closed test shapes (`shapes`), textured scenes (`textured`) and
large assembly files written for the benchmarks (`assembly`). Imports the scene model only.
"""
