"""If/unless conditions, evaluated per resolve, each reporting what it read."""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import ArgumentError, Origin, caller_origin
from .substitutions import (
    LaunchConfiguration,
    PerformContext,
    SimpleSubstitution,
    SubValue,
    describe,
    flatten,
    perform,
    text_to_bool,
)


@dataclass(frozen=True)
class ConditionOutcome:
    """What a condition read and decided: shown for skipped branches and in the tree."""

    expression: str
    value: str
    holds: bool

    def to_json(self) -> dict[str, object]:
        return {"expression": self.expression, "value": self.value, "holds": self.holds}


def _argument_name(predicate: SubValue) -> str | None:
    parts = flatten(predicate)
    while len(parts) == 1 and isinstance(parts[0], SimpleSubstitution):
        parts = parts[0].parts
    if len(parts) == 1 and isinstance(parts[0], LaunchConfiguration):
        return parts[0].name()
    return None


class Condition:
    origin: Origin | None = None

    def evaluate(self, context: PerformContext) -> ConditionOutcome:
        raise NotImplementedError

    def describe(self) -> str:
        return type(self).__name__


class IfCondition(Condition):
    negate = False

    def __init__(self, predicate_expression: SubValue) -> None:
        self.predicate = predicate_expression
        self.origin = caller_origin()

    def describe(self) -> str:
        word = "unless" if self.negate else "if"
        return f"{word} {describe(self.predicate)}"

    def evaluate(self, context: PerformContext) -> ConditionOutcome:
        if isinstance(self.predicate, bool):
            text = str(self.predicate).lower()
        else:
            text = perform(self.predicate, context)
        value = text_to_bool(text)
        if value is None:
            name = _argument_name(self.predicate)
            if name is not None:
                raise ArgumentError(
                    f"argument '{name}' = {text!r} is used as a condition but is not a boolean",
                    self.origin,
                    hint=f"pass {name}:=true or {name}:=false",
                )
            raise ArgumentError(
                f"condition {describe(self.predicate)} gave {text!r}, which is not a boolean",
                self.origin,
                hint="a condition must read true, false, 1 or 0",
            )
        holds = (not value) if self.negate else value
        return ConditionOutcome(self.describe(), text, holds)


class UnlessCondition(IfCondition):
    negate = True


class LaunchConfigurationEquals(Condition):
    negate = False

    def __init__(self, launch_configuration_name: str, expected_value: SubValue) -> None:
        self.name = launch_configuration_name
        self.expected = expected_value
        self.origin = caller_origin()

    def describe(self) -> str:
        op = "!=" if self.negate else "=="
        return f"$(var {self.name}) {op} {describe(self.expected)!r}"

    def evaluate(self, context: PerformContext) -> ConditionOutcome:
        value = context.configurations.get(self.name, "")
        expected = "" if self.expected is None else perform(self.expected, context)
        equal = value == expected
        return ConditionOutcome(self.describe(), value, equal != self.negate)


class LaunchConfigurationNotEquals(LaunchConfigurationEquals):
    negate = True


def as_condition(value: object, negate: bool = False) -> Condition:
    """Anything a user may pass as a condition (bool, substitution, Condition)."""
    if isinstance(value, Condition):
        return value
    return UnlessCondition(value) if negate else IfCondition(value)
