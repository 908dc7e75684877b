"""Makes the win_amd64 wheel of one CPython version from the Linux wheel that scikit-build-core built from
pyproject.toml for the same version, with the compiled core swapped for the mingw-w64 build of it:

    python3 scripts/windows_wheel.py --linux-wheel build/wheels/meniscus-V-cp311-cp311-linux_x86_64.whl \
        --core build-wheel-win-cp311/python/meniscus/_core.cp311-win_amd64.pyd --out dist

Everything but the core (the Python modules, METADATA, the `meniscus` console script in entry_points.txt, the
licence) is the Linux wheel's, so the two platforms cannot drift apart; only the WHEEL tag and RECORD are rewritten.
Called by scripts/package_windows.sh. Prints the wheel's path.
"""
import argparse
import base64
import hashlib
import pathlib
import re
import zipfile


def record_line(name, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{name},sha256={digest},{len(data)}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--linux-wheel", required=True, type=pathlib.Path)
    parser.add_argument("--core", required=True, type=pathlib.Path, help="the _core.cpXY-win_amd64.pyd to ship")
    parser.add_argument("--out", required=True, type=pathlib.Path)
    args = parser.parse_args()

    match = re.fullmatch(r"(meniscus-[0-9.]+)-(cp3\d+)-(cp3\d+)-linux_x86_64\.whl", args.linux_wheel.name)
    if not match:
        raise SystemExit(f"{args.linux_wheel.name}: not a raw (pre-auditwheel) Linux wheel of meniscus")
    stem, python_tag, abi_tag = match.groups()
    if args.core.name != f"_core.{python_tag}-win_amd64.pyd":
        raise SystemExit(f"{args.core.name}: not the compiled core for {python_tag} on win_amd64")
    tag = f"{python_tag}-{abi_tag}-win_amd64"
    target = args.out / f"{stem}-{tag}.whl"
    dist_info = f"{stem}.dist-info"

    records = []
    with zipfile.ZipFile(args.linux_wheel) as source, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as wheel:
        def add(name, data):
            wheel.writestr(name, data)
            records.append(record_line(name, data))

        for name in source.namelist():
            if name == f"{dist_info}/RECORD" or re.match(r"meniscus/_core\.[^/]+\.so$", name):
                continue
            if name.startswith("meniscus.libs/"):
                raise SystemExit(f"{args.linux_wheel.name} vendors libraries: give the wheel from before auditwheel")
            data = source.read(name)
            if name == f"{dist_info}/WHEEL":
                data = re.sub(rb"^Tag: .*$", f"Tag: {tag}".encode(), data, flags=re.M)
            add(name, data)
        add(f"meniscus/{args.core.name}", args.core.read_bytes())
        records.append(f"{dist_info}/RECORD,,")
        wheel.writestr(f"{dist_info}/RECORD", "\n".join(records) + "\n")
    print(target)


if __name__ == "__main__":
    main()
