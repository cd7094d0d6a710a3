"""The typed error of a sweep figure's options (``quantity``, ``x``, ``y``, ``panels``,
``at``): it carries what a message needs (the problem, the option, the key, the values), and
words itself with the options named as a caller names them: Python keywords in its own
message (``at``), the command line's options in ``rodjit/cli/wording.py`` (``--at``).
"""
from __future__ import annotations

from typing import Any, Callable

__all__ = ["BadPlotOption"]

# each problem's message; ``{o}`` is the option, ``{at}`` the option that fixes keys
_TEXTS = {
    "quantity": "{o} {value!r} is not a numeric summary column (one of {choices})",
    "not_swept": "{o} {value!r} is not a swept key (swept: {choices})",
    "fixes_free": "{o} {value} fixes the key the figure runs along",
    "off_grid": "{o} {value} is not on the grid ({choices})",
    "panels_taken": "{o} {value} is already the x axis or fixed by {at}",
    "too_many_panels": "{o} {value}: {choices}",
    "too_many_lines": "{value} are too many to draw; fix some keys with {at} KEY=VALUE",
    "no_heatmap_keys": "a heatmap needs two swept keys with several values that {at} does "
                       "not fix (swept: {choices})",
    "heatmap_only": "{o} is for heatmaps",
    "restitution_only": "{o} is for the restitution kind",
}


class BadPlotOption(ValueError):
    """A sweep figure's option that cannot be drawn as given.

    Parameters
    ----------
    problem : str
        Which refusal (a key of ``_TEXTS``): ``"quantity"``, ``"not_swept"``,
        ``"fixes_free"``, ``"off_grid"``, ``"panels_taken"``, ``"too_many_panels"``,
        ``"too_many_lines"``, ``"no_heatmap_keys"``, ``"heatmap_only"``,
        ``"restitution_only"``.
    option : str
        The option, as its keyword (``"at"``, ``"x"``); empty when the problem is no one
        option's.
    value : object, optional
        What was given (a key, ``"rod.mu=0.3"``, a count of lines).
    choices : str, optional
        What could be given, or the rest of the message (the swept keys, the grid's values).
    """

    def __init__(self, problem: str, option: str = "", value: Any = "",
                 choices: str = "") -> None:
        self.problem, self.option, self.value, self.choices = problem, option, value, choices
        super().__init__(self.worded(lambda keyword: keyword))

    def worded(self, name: Callable[[str], str]) -> str:
        """The message, each option named by ``name`` (its keyword -> the text)."""
        return _TEXTS[self.problem].format(o=name(self.option), at=name("at"), value=self.value,
                                           choices=self.choices)

    def __reduce__(self):
        return type(self), (self.problem, self.option, self.value, self.choices)
