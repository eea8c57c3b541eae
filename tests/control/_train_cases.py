"""examples/train_emulator.py run up to its campaign: every check of its arguments, no
simulation (shared by the script's tests)."""

from tests._examples import load_example


class CampaignReached(Exception):
    """Raised where the script would start its campaign: every check passed."""


def run_until_the_campaign(monkeypatch, tmp_path, argv) -> None:
    """train_emulator.main(argv) with the campaign replaced: CampaignReached where every check
    passed."""
    script = load_example("train_emulator")

    def campaign(*args, **kwargs):
        raise CampaignReached

    monkeypatch.setattr(script.vehicle, "run_campaign", campaign)
    script.main([*argv, "--out", str(tmp_path / "out")])
