from fepen.cli import main

raise SystemExit(main())
