"""Old import path of :mod:`engine.solver`, kept while other branches move over (issue 11).

New code imports from :mod:`engine.solver`; remove this module once nothing uses it.
"""

from engine.solver import FULL_SET, MODES, OPTIMIZERS, FrameContext, OptimizerSettings, PoseOptimizer, Solution

__all__ = ["FULL_SET", "MODES", "OPTIMIZERS", "FrameContext", "OptimizerSettings", "PoseOptimizer", "Solution"]
