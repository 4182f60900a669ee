"""The FMI interface: breadth (2.0, 3.0, CS, ME, states), state rules, inputs inside a step, output derivatives."""
