"""What will run for given argument values: resolving a Description into a Plan,
parameters, packages."""
