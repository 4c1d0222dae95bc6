"""The physics of the double pendulum, in pure Python (the FMU bundles it).

:mod:`.parameters` (units, defaults, checks), :mod:`.kinematics` (positions, velocities),
:mod:`.dynamics` (Lagrange equations of the fixed-pivot pendulum), :mod:`.forces` (air drag,
bearing friction), :mod:`.energy`, :mod:`.scene` (a scene's switches and states),
:mod:`.evaluator` (the general evaluator of its equations, in named parts), :mod:`.vector_field`
(a scene's assembled vector field with friction, suspension and inputs), :mod:`.inputs` (pivot
motion and joint torques, their hold over a communication step), :mod:`.outputs` (the quantities
reported at each communication point), :mod:`.quantities` (the :class:`~.quantities.Quantity`
record inputs and outputs are listed as) and :mod:`.suspension` (the suspension on its own, the
``Suspension`` FMU's model).
"""
