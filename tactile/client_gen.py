"""The service's OpenAPI schema and the generated client kept in step with it.

``python -m tactile.client_gen`` dumps the schema (default settings) and regenerates
``hardware_sim/api_client`` with openapi-python-client; a test does the same into a
temporary folder and fails if anything differs from what is committed.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from app.main import create_app
from app.settings import Settings

__all__ = ["CLIENT_DIR", "generate_client", "openapi_schema"]

ROOT = Path(__file__).resolve().parents[1]
CLIENT_DIR = ROOT / "hardware_sim" / "api_client"
CONFIG = ROOT / "hardware_sim" / "api_client_config.yaml"


def openapi_schema() -> dict:
    """The schema of an app built with default settings (limits appear in it)."""
    return create_app(Settings(api_key=None)).openapi()


def generate_client(output: Path) -> None:
    """Generate the Python client for the current schema into `output` (replaced)."""
    generator = Path(sys.executable).with_name("openapi-python-client")
    with tempfile.TemporaryDirectory() as tmp:
        schema = Path(tmp) / "openapi.json"
        schema.write_text(json.dumps(openapi_schema(), indent=1, sort_keys=True))
        target = Path(tmp) / "client"
        subprocess.run(
            [
                str(generator),
                "generate",
                "--path",
                str(schema),
                "--meta",
                "none",
                "--config",
                str(CONFIG),
                "--output-path",
                str(target),
            ],
            check=True,
            capture_output=True,
            text=True,
        )
        if output.exists():
            shutil.rmtree(output)
        shutil.copytree(target, output)


if __name__ == "__main__":
    generate_client(CLIENT_DIR)
    print(f"regenerated {CLIENT_DIR.relative_to(ROOT)}")
