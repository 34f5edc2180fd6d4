from fepen.cli import console

console()
