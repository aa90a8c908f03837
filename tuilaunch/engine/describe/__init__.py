"""What a launch file says: the DSL, the launch API entities, substitutions, conditions,
and loading files."""
