"""Model files the tests share, as text."""

#: the planar pendulum in Cartesian coordinates: a holonomic constraint
#: g = x^2 + y^2 - l^2 and gravity along -y (no initial state)
PENDULUM_XY = """
name = "pendulum in x, y"
coordinates = ["x", "y"]
lagrangian = "(x_t**2 + y_t**2)/2 - G*y"
constraints = ["x**2 + y**2 - l**2"]
[parameters]
G = 9.81
l = 1.0
"""


#: PENDULUM_XY with an initial state on the circle
PENDULUM_XY_STARTED = PENDULUM_XY + """[initial]
x = 0.6
y = -0.8
x_t = 1.0
"""
